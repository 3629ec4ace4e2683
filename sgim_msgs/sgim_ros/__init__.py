"""ROS glue shared by every node of the graph: QoS of the records and parameter checks."""
