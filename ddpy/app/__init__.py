"""The application: the ``ddpy`` command line, the runner that drives a case's phases with
output and checkpoints, and the post-processing of its results."""
