"""What a run looks like from the outside: the live picture that the web teacher and the
markers node draw (picture.py, pure Python) and its ROS markers (markers.py)."""
