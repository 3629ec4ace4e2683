"""ROS-free learner core: every formula of SGIM-D / SAGG-RIAC as plain, testable Python.

Kept free of rclpy so that unit tests, benchmarks and the single-process runner need no ROS;
the ROS nodes only drive these objects movement by movement.
"""
