"""Bags: the record types and their one validation (validation.py), the writer of one chunked
MCAP file per recording, the readers (reader.py, mcap_recovery.py for a file a kill left
unfinished, run_folder.py for a run's segments), and the tools built on them (rebuild, resume,
replay, repair). ROS-free except replay, which publishes."""
