"""A reader that stops early (``poc-env policies | head -1``) is no error (the wheel check's
``grep -q`` on a listing ended in a BrokenPipeError traceback and exit status 1)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path


def test_a_closed_pipe_ends_the_listing_quietly():
    exe = shutil.which("poc-env", path=str(Path(sys.executable).parent))
    assert exe is not None
    # a reader that reads one byte and leaves, while the listing is still being written
    done = subprocess.run(
        ["bash", "-o", "pipefail", "-c", f"'{exe}' policies | head -c 1 > /dev/null"],
        capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "BrokenPipeError" not in done.stderr
