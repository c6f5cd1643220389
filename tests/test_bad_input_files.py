"""Files nothing is silently wrong about (issue 19): tampered attributes refused by load and
by ``impactcont info``/``plot``, files of ``save(validate=False)``, and a save killed with
``kill -9`` leaving no process nor temporary file behind."""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

import pytest
from test_files import _start_save, _temporaries


# -- a killed save -----------------------------------------------------------------------------
def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (Linux /proc)."""
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                status = Path(f"/proc/{entry}/status").read_text()
            except OSError:
                continue
            fields = dict(line.split(":\t", 1) for line in status.splitlines() if ":\t" in line)
            if fields.get("PPid", "").strip() == str(pid):
                out.append(int(entry))
    return out


def _alive(pid: int) -> bool:
    """``pid`` runs (a zombie has ended: it only waits to be reaped by init)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_kill_9_of_a_saving_process_ends_its_writer_and_removes_the_temporary(
        tmp_path: Path) -> None:
    """The write of a large dataset runs in a child process: it must end with its parent.

    It once went on as an orphan, writing the temporary file to the end (1 GB in the
    report), which only the next save in that directory removed.
    """
    target = tmp_path / "big.nc"
    proc = _start_save(target, 6, "fork")  # 60 MB in memory: about 2 s of writing in a child
    (writer,) = _children(proc.pid)
    try:
        proc.kill()
        proc.communicate(timeout=30)
        start = time.monotonic()
        while (_alive(writer) or _temporaries(tmp_path)) and time.monotonic() - start < 3.0:
            time.sleep(0.01)
        assert not _alive(writer), "the writing child survived its parent's kill -9"
        assert _temporaries(tmp_path) == [], "the killed save left its temporary file"
        assert not target.exists()
    finally:
        if _alive(writer):  # only before the fix: do not leave it writing
            os.kill(writer, signal.SIGKILL)
