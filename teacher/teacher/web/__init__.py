"""The web teacher: a live page of the run that takes demonstrations (web_teacher_node)."""
