"""Where runs and figures come from: the learner fingerprint and the provenance block."""
