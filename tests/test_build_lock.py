"""prsc.files.building: two processes building the same cache file (two compile workers asking
for one arm's reach ring) take turns, so the second finds the file built instead of building it."""

from __future__ import annotations

import subprocess
import sys
import time

from prsc.files import building

CHILD = """
import sys, time
from pathlib import Path
from prsc.files import building
path = Path(sys.argv[1])
with building(path):
    Path(sys.argv[2]).write_text(str(time.monotonic()))
"""


def test_a_second_builder_waits_for_the_first(tmp_path):
    target, entered = tmp_path / "ring.json", tmp_path / "entered"
    with building(target):
        child = subprocess.Popen([sys.executable, "-c", CHILD, str(target), str(entered)])
        time.sleep(1.0)
        assert not entered.exists()  # still waiting for the lock this process holds
        released = time.monotonic()
    assert child.wait(timeout=30) == 0
    assert float(entered.read_text()) >= released


def test_a_killed_builder_does_not_block_the_next(tmp_path):
    target = tmp_path / "ring.json"
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\nfrom pathlib import Path\n"
                               "from prsc.files import building\nwith building(Path(sys.argv[1])):\n"
                               "    print('held', flush=True); time.sleep(60)", str(target)],
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    holder.kill()
    holder.wait()
    with building(target):  # the lock died with its process
        pass
