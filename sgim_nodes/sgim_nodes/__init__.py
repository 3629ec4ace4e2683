"""sgim_nodes: the learner of the SGIM-D / SAGG-RIAC toolkit (ROS nodes live beside ``core``)."""
