"""Suite-wide set-up: the command line compiles in this process on a machine whose kernels are not
compiled yet (``CRASHSIM_FIRST_RUN=wait``), so that commands called in-process run in-process (their
output captured); ``tests/unit/test_first_run.py`` tests the other policies in child processes."""

import os

os.environ.setdefault("CRASHSIM_FIRST_RUN", "wait")
