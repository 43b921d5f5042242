#!/usr/bin/python3
"""Times what a new user waits for: scripts/demo.sh and scripts/test.sh on a fresh clone of this checkout
(ccache disabled, Debian packages already installed), then re-renders docs/RESULTS.md.

  scripts/measure_build_times.py        (about 30 minutes on 2 cores)

Writes docs/results/build_times.json; workflows/scripts/publish.py shows it in docs/RESULTS.md.
The clone is made beside this checkout (so that ../shared is found as in any checkout) and removed.
"""
import datetime
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "workflows", "scripts"))
from run_job import machine  # noqa: E402


def timed_lines(command, cwd, env, marks):
    """Runs command, echoing its output; returns the total seconds and, per mark regex, when it first showed."""
    start = time.monotonic()
    seen = {}
    p = subprocess.Popen(command, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    for line in p.stdout:
        sys.stderr.write(line)
        for key, pattern in marks.items():
            if key not in seen and re.search(pattern, line):
                seen[key] = time.monotonic() - start
    if p.wait() != 0:
        raise SystemExit(f"measure_build_times: {' '.join(command)} failed in {cwd}")
    return time.monotonic() - start, seen


def main():
    shared = os.environ.get("CROWDSLAM_SHARED", os.path.join(REPO, "..", "shared"))
    fresh = tempfile.mkdtemp(prefix="crowdslam-fresh-", dir=os.path.dirname(REPO))
    try:
        subprocess.run(["git", "clone", "-q", "--no-local", REPO, fresh], check=True)
        env = dict(os.environ, CCACHE_DISABLE="1", CROWDSLAM_SHARED=os.path.abspath(shared))
        demo_s, demo = timed_lines(["bash", "scripts/demo.sh"], fresh, env,
                                   {"cli_built": r"setup: default vocabulary", "result": r"^ATE RMSE"})
        test_s, test = timed_lines(["bash", "scripts/test.sh"], fresh, env, {"suite_start": r"^Test project"})
    finally:
        shutil.rmtree(fresh, ignore_errors=True)
    commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--short=12", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    m = machine()
    result = {"date": datetime.date.today().isoformat(), "commit": commit,
              "machine": f"{m['cpu']}, {m['cores_usable']} cores, {m['mem_gb']} GB RAM, Linux {m['kernel']}",
              "demo_total_s": demo_s, "demo_cli_built_s": demo.get("cli_built"), "demo_result_s": demo.get("result"),
              "test_total_s": test_s, "test_build_s": test.get("suite_start"),
              "suite_s": test_s - test["suite_start"] if "suite_start" in test else None}
    os.makedirs(os.path.join(REPO, "docs", "results"), exist_ok=True)
    with open(os.path.join(REPO, "docs", "results", "build_times.json"), "w") as f:
        json.dump(result, f, indent=1)
    subprocess.run(["/usr/bin/python3", os.path.join(REPO, "workflows", "scripts", "publish.py"), "--render-only"],
                   check=True)


if __name__ == "__main__":
    main()
