"""teacher: the automatic teacher of SGIM-D (its ROS node lives beside ``teaching``)."""
