"""The ROS 2 nodes of the learner: each translates messages to the ROS-free core and back."""
