"""Shared fixtures of the Python API tests (tests/python/CMakeLists.txt runs each file under CTest).

Environment (set by CTest, see CMakeLists.txt): PYTHONPATH (build/python), CROWDSLAM_CLI (the built
`crowdslam`), CROWDSLAM_SOURCE_DIR, CROWDSLAM_SHARED_DIR (compile-time ../shared; CROWDSLAM_SHARED
overrides it, as for the C++ tests).
"""
from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

import crowdslam

SOURCE_DIR = Path(os.environ.get("CROWDSLAM_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CLI = Path(os.environ.get("CROWDSLAM_CLI", SOURCE_DIR / "build/apps/crowdslam/crowdslam"))
SHARED = Path(os.environ.get("CROWDSLAM_SHARED") or os.environ.get("CROWDSLAM_SHARED_DIR") or SOURCE_DIR / "../shared")

# A short synthetic RGB-D sequence with walking people (rendered by `crowdslam synth`): enough for the map
# to initialise, create keyframes and track, fast enough for every test file to use it.
SYNTH_ARGS = ["--frames", "60", "--people", "2", "--width", "320", "--height", "240", "--seed", "7"]


def run_cli(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    result = subprocess.run([str(CLI), *args], capture_output=True, text=True, timeout=600)
    if check and result.returncode != 0:
        raise AssertionError(f"crowdslam {' '.join(args)} exited {result.returncode}:\n{result.stderr}")
    return result


def cli_json(*args: str) -> dict:
    return json.loads(run_cli("--json", *args).stdout)


def models_available() -> bool:
    try:
        crowdslam.Detector("body")
        return True
    except crowdslam.InputError:
        return False


def vocabulary_available() -> bool:
    path = os.environ.get("CROWDSLAM_VOCABULARY") or SOURCE_DIR / "vocabulary" / "crowdslam_orb.voc"
    return Path(path).is_file()


@pytest.fixture(scope="session")
def synth_sequence() -> Path:
    """The synthetic sequence, rendered once and shared by the test files (a lock serialises CTest's
    parallel processes; the key changes when the CLI is rebuilt)."""
    if not CLI.is_file():
        pytest.skip(f"{CLI} not built")
    key = hashlib.sha1(f"{CLI.stat().st_mtime_ns} {' '.join(SYNTH_ARGS)}".encode()).hexdigest()[:12]
    root = Path(tempfile.gettempdir()) / f"crowdslam-pytest-{os.getuid()}"
    root.mkdir(exist_ok=True)
    target = root / f"synth-{key}"
    with open(root / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (target / "rgb.txt").is_file():
            partial = root / f"synth-{key}.partial"
            shutil.rmtree(partial, ignore_errors=True)
            run_cli("--quiet", "synth", "--out", str(partial), *SYNTH_ARGS, "--force")
            partial.rename(target)
    return target


@pytest.fixture(scope="session")
def synth_settings(synth_sequence: Path) -> Path:
    return synth_sequence / "settings.yaml"


def shared_data(name: str) -> Path:
    path = SHARED / "data" / name
    if not path.is_dir():
        pytest.skip(f"{path} not available")
    return path
