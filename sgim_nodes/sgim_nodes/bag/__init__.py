"""Bags: the record types, the writer, the readers, and the tools built on them (rebuild,
resume, replay). ROS-free except replay, which publishes."""
