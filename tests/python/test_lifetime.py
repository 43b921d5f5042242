"""The SLAM threads stop on close, on garbage collection and when the interpreter exits mid-run."""
from __future__ import annotations

import gc
import os
import re
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import crowdslam


def native_threads() -> int:
    return len(os.listdir("/proc/self/task"))


def script(synth_sequence: Path, body: str) -> str:
    return textwrap.dedent(f"""
        import crowdslam
        seq = crowdslam.datasets.open({str(synth_sequence)!r})
        slam = crowdslam.System({str(synth_sequence / 'settings.yaml')!r},
                                detections={str(synth_sequence / 'people_gt.txt')!r})
        frames = iter(seq)
        for _ in range(8):
            f = next(frames)
            slam.track(f.image, f.depth, timestamp=f.timestamp)
    """) + textwrap.dedent(body)


@pytest.mark.parametrize("ending", [
    "",                                    # falls off the end: the System is a global never closed
    "import sys\nsys.exit(0)\n",           # sys.exit mid-run
    "import threading\n"                   # a daemon thread still tracking when the main thread ends
    "def more():\n"
    "    for f in frames:\n"
    "        slam.track(f.image, f.depth, timestamp=f.timestamp)\n"
    "threading.Thread(target=more, daemon=True).start()\n",
])
def test_interpreter_exits_cleanly_mid_run(synth_sequence: Path, ending: str) -> None:
    # A hang is the failure to catch (subprocess.run raises TimeoutExpired); the limit is generous so a
    # loaded machine does not fail it.
    result = subprocess.run([sys.executable, "-c", script(synth_sequence, ending)], capture_output=True, text=True,
                            timeout=180, env=os.environ)
    assert result.returncode == 0, result.stderr
    assert "terminate" not in result.stderr and "Abort" not in result.stderr
    if "daemon" in ending:
        # The daemon thread's next track() after the atexit hook stopped the System raises and says so. The
        # interpreter may freeze that thread while it prints the traceback (CPython stops daemon threads at
        # finalisation), so a traceback can be cut short; any exception line it does print must be ours.
        assert "Fatal Python error" not in result.stderr and "Segmentation" not in result.stderr
        raised = [line for line in result.stderr.splitlines() if re.match(r"^[A-Za-z_.]+(Error|Exception)\b", line)]
        assert all("stopped and destroyed at interpreter exit" in line for line in raised), result.stderr
    else:
        assert "Traceback" not in result.stderr


def test_threads_stop_on_close_and_on_collection(synth_sequence: Path, synth_settings: Path) -> None:
    seq = crowdslam.datasets.open(synth_sequence)
    frames = [seq[i] for i in range(5)]

    def run_one(close: bool) -> None:
        slam = crowdslam.System(synth_settings, detections=str(synth_sequence / "people_gt.txt"))
        for f in frames:
            slam.track(f.image, f.depth, timestamp=f.timestamp)
        assert native_threads() > before  # local mapping, loop closing, detector
        if close:
            slam.close()
            slam.trajectory()  # still readable
        del slam
        gc.collect()

    before = 0
    run_one(True)  # warm-up: OpenCV's and BLAS's own pools start once per process and stay
    before = native_threads()
    for close in (True, False):
        run_one(close)
        for _ in range(400):  # threads told to stop may take a moment to be reaped
            if native_threads() == before:
                break
            time.sleep(0.05)
        assert native_threads() == before


def test_context_manager_closes(synth_sequence: Path, synth_settings: Path) -> None:
    f = crowdslam.datasets.open(synth_sequence)[0]
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as slam:
        assert not slam.closed
        slam.track(f.image, f.depth, timestamp=f.timestamp)
    assert slam.closed
    assert slam.trajectory().shape == (1, 8)
    with pytest.raises(RuntimeError, match="closed"):
        slam.track(f.image, f.depth, timestamp=1.0)
    # An exception inside the block closes it too, and propagates.
    with pytest.raises(KeyError):
        with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as other:
            raise KeyError("inside")
    assert other.closed
