"""The evaluation workflow (workflows/): a dry run of every shipped matrix, the smoke matrix end to end
(its table against the individual run.json / time.json files), and a job killed mid-run.

Environment (set by CTest, tests/workflow/CMakeLists.txt): CROWDSLAM_CLI (the crowdslam binary),
CROWDSLAM_SOURCE_DIR, CROWDSLAM_SHARED_DIR (../shared), SNAKEMAKE (the snakemake command).
By hand: CROWDSLAM_CLI=/path/to/crowdslam python3 -m pytest -v -p no:cacheprovider tests/workflow
"""
import csv
import glob
import json
import os
import signal
import statistics
import subprocess
import sys
import time

import pytest

SOURCE = os.environ.get("CROWDSLAM_SOURCE_DIR") or os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))
CLI = os.environ.get("CROWDSLAM_CLI") or os.path.join(SOURCE, "build", "apps", "crowdslam", "crowdslam")
SHARED = os.environ.get("CROWDSLAM_SHARED_DIR") or os.environ.get("CROWDSLAM_SHARED") or os.path.join(
    SOURCE, "..", "shared")
SNAKEMAKE = os.environ.get("SNAKEMAKE", "snakemake")
SNAKEFILE = os.path.join(SOURCE, "workflows", "Snakefile")
MATRICES = sorted(glob.glob(os.path.join(SOURCE, "workflows", "matrices", "*.yaml")))
sys.path.insert(0, os.path.join(SOURCE, "workflows", "scripts"))
import aggregate  # noqa: E402

ENV = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")

pytestmark = pytest.mark.skipif(not os.access(CLI, os.X_OK), reason=f"{CLI} not built")


def snakemake(work, matrix, *extra, cli=CLI, env=ENV, config=(), **kw):
    cmd = [SNAKEMAKE, "-s", SNAKEFILE, "--directory", str(work), "--configfile", matrix, "--config",
           f"results={work}/results", f"crowdslam={cli}", f"shared={SHARED}"] + list(config) + list(extra)
    return subprocess.run(cmd, env=env, capture_output=True, text=True, **kw)


@pytest.mark.parametrize("matrix", MATRICES, ids=[os.path.basename(m)[:-5] for m in MATRICES])
def test_dry_run(tmp_path, matrix):
    if "{shared}" in open(matrix).read() and not os.path.isdir(os.path.join(SHARED, "data")):
        pytest.skip(f"{SHARED}/data not found")
    r = snakemake(tmp_path, matrix, "-n", "-q")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Job stats" in r.stdout + r.stderr


PARTS = sorted(glob.glob(os.path.join(SOURCE, "workflows", "matrices", "parts", "*.yaml")))


@pytest.mark.parametrize("part", PARTS, ids=[os.path.basename(p)[:-5] for p in PARTS])
def test_a_part_selects_crowd_cases_with_their_empty_rooms(tmp_path, part):
    # A part (parts/*.yaml) replaces its base matrix's `cases:`; every crowd case it selects must have its
    # empty room in the selection too, or the table has no "ATE / empty" for it.
    import matrix as mx
    import yaml
    base = os.path.join(SOURCE, "workflows", "matrices", "synthetic_crowd.yaml")
    assert "synthetic_crowd.yaml" in open(part).read(), "a part names its base matrix"
    config = yaml.safe_load(open(base))
    config.update(yaml.safe_load(open(part)))
    m = mx.Matrix(config, repo=SOURCE, results=str(tmp_path))
    assert m.cases, f"{part} selects no case"
    for name, case in m.cases.items():
        if m.datasets[case["dataset"]].get("baseline"):  # a crowd case (the empty rooms have none)
            assert m.baseline(name), f"{name}: its empty room is not selected"


def test_a_list_of_grids_expands_to_the_union_of_their_products(tmp_path):
    import matrix as mx
    config = {"matrix": "grids", "datasets": {"{crowd}_{people}": {
        "grid": [{"crowd": ["passing", "standing"], "people": [8, 16]}, {"crowd": ["near"], "people": [8]}],
        "synth": "--crowd {crowd} --people {people}"}}, "options": {"default": ""}}
    m = mx.Matrix(config, repo=SOURCE, results=str(tmp_path))
    assert sorted(m.datasets) == ["near_8", "passing_16", "passing_8", "standing_16", "standing_8"]
    assert m.datasets["near_8"]["synth"] == ["--crowd", "near", "--people", "8"]
    assert len(m.cases) == 5
    config["datasets"]["{crowd}_{people}"]["grid"] = [{"crowd": ["near"]}, ["people"]]
    with pytest.raises(mx.MatrixError, match="grid"):
        mx.Matrix(config, repo=SOURCE, results=str(tmp_path))


def test_the_crowd_table_puts_each_crowd_case_beside_its_empty_room():
    import publish

    def case(dataset, options, ate, baseline=None, complete=5):
        stats = {k: {"median": v} for k, v in (("tracked_percent", 97.5), ("map_resets", 0), ("reanchors", 1),
                                                ("bridged_frames", 4), ("ate_m", ate), ("fps", 50.0))}
        return ({"dataset": dataset, "options": options, "baseline": baseline},
                {"complete": complete, "stats": stats, "ate_ratio": ate / 0.004 if baseline and ate else None})
    cases = {"standing_8_s5.default.body_mono": case("standing_8_s5", "body_mono", 0.02, "standing_8_s5_empty.default.empty_mono"),
             "standing_8_s5_empty.default.empty_mono": case("standing_8_s5_empty", "empty_mono", 0.004),
             "passing_16_s5_stereo.default.gt": case("passing_16_s5_stereo", "gt", 0.008, "passing_16_s5_stereo_empty.default.empty"),
             "passing_16_s5_stereo_empty.default.empty": case("passing_16_s5_stereo_empty", "empty", 0.004),
             "passing_16_s5.default.yolox": case("passing_16_s5", "yolox", None, "passing_16_s5_empty.default.empty", 0)}
    table = {"matrix": {"matrix": "synthetic_crowd", "mode": "timing", "runs": 5,
                        "cases": {k: v[0] for k, v in cases.items()}},
             "cases": {k: v[1] for k, v in cases.items()},
             "provenance": {"last": "2026-12-06", "machines": ["vm: AMD EPYC, 2 of 2 cores"], "builds": ["x"]}}
    rows = [line for line in publish.crowds_table(table).splitlines() if line.startswith("| ") and "---" not in line][1:]
    # Passing before standing; the empty rooms are not rows of their own but the column beside their crowd.
    assert [r.split(" | ")[:5] for r in rows] == [["| passing", "16", "5", "rgbd", "yolox"],
                                                ["| passing", "16", "5", "stereo", "gt"],
                                                ["| standing", "8", "5", "mono", "body"]]
    assert rows[1].split(" | ")[10:13] == ["0.0080", "0.0040", "2.0x"]
    assert rows[2].split(" | ")[5:13] == ["5/5", "97.5", "0", "1", "4", "0.0200", "0.0040", "5.0x"]
    assert rows[0].split(" | ")[5] == "0/5" and "n/a" in rows[0]


def test_the_detection_table_reads_each_configuration_from_its_detect_arguments():
    import publish

    def counts(tp, fp, fn):
        return {"precision": tp / (tp + fp), "recall": tp / (tp + fn), "moda": 1 - (fp + fn) / (tp + fn),
                "modp": 0.7, "tp": tp, "fp": fp, "fn": fn}
    detection = {"iou": 0.5, "sequences": {"A": {}, "B": {}}, "configs": {
        "yolox_raw": {"public": False, "args": ["--model", "yolox", "--input", "416x320", "--confidence", "0.3",
                                                "--nms", "0.45", "--raw"]},
        "body_default": {"public": False, "args": ["--input", "160"]},
        "public": {"public": True, "args": []}}}
    configs = {"yolox_raw": {"complete": 2, "sequences": {"A": counts(8, 2, 2), "B": counts(1, 0, 3)},
                             "all": counts(9, 2, 5), "ms_per_frame": 41.25},
               "body_default": {"complete": 0, "sequences": {}, "all": {}},
               "public": {"complete": 2, "sequences": {"A": counts(5, 5, 5), "B": counts(4, 0, 0)},
                          "all": counts(9, 5, 5), "ms_per_frame": None}}
    table = {"matrix": {"matrix": "detectors", "detection": detection}, "configs": configs,
             "provenance": {"last": "2026-12-06", "machines": ["vm"]}}
    rows = [line for line in publish.detection_table(table).splitlines() if line.startswith("| ")][2:]
    cells = [r.split(" | ") for r in rows]
    # Model, input, thresholds and NMS stage from the detect arguments; pooled figures from the summed counts.
    assert cells[0][:4] == ["| yolox", "416x320", "0.3 / 0.45", "before NMS"]
    assert cells[0][4] == "81.8 / 64.3 / 50.0 / 70.0"  # 9 / 11, 9 / 14, 1 - 7 / 14
    assert cells[0][5] == "60.0 / 25.0" and cells[0][6] == "41.2 |"
    assert "not measured" in rows[1]
    assert cells[2][:4] == ["| MOT15 public det/det.txt", "-", "all", "after NMS"] and cells[2][6] == "n/a |"


def smoke_matrix():
    return os.path.join(SOURCE, "workflows", "matrices", "smoke.yaml")


def medians_from_runs(results):
    """Medians computed here, from each complete run directory's own files."""
    out = {}
    for case_dir in sorted(glob.glob(os.path.join(results, "smoke", "*.*.*"))):
        values = {}
        for run in sorted(glob.glob(os.path.join(case_dir, "[0-9]*"))):
            if not os.path.isdir(run) or ".tmp-" in run:
                continue
            doc = json.load(open(os.path.join(run, "run.json")))
            timing = json.load(open(os.path.join(run, "time.json")))
            s, a = doc["summary"], doc["accuracy"]
            for key, value in (("ate_m", a["ate_rmse_m"]), ("rpe_m_per_s", a["rpe_trans_rmse_m_per_s"]),
                               ("tracked_percent", s["tracked_percent"]), ("map_resets", s["map_resets"]),
                               ("fps", s["throughput_fps"]), ("cpu_s_per_frame", timing["cpu_s"] / s["frames"]),
                               ("peak_rss_mb", timing["peak_rss_kb"] / 1024)):
                values.setdefault(key, []).append(value)
        out[os.path.basename(case_dir)] = {k: statistics.median(v) for k, v in values.items()}
    return out


def test_smoke_end_to_end(tmp_path):
    r = snakemake(tmp_path, smoke_matrix(), "--cores", "2", timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    results = tmp_path / "results"
    table = json.load(open(results / "smoke" / "table.json"))
    rows = {row["case"]: row for row in csv.DictReader(open(results / "smoke" / "table.csv"))}
    expected = medians_from_runs(results)
    assert len(expected) == 4 and set(rows) == set(expected) == set(table["cases"])
    for case, medians in expected.items():
        assert table["cases"][case]["complete"] == 2 and rows[case]["runs"] == "2"
        for key, value in medians.items():
            assert table["cases"][case]["stats"][key]["median"] == pytest.approx(value, rel=1e-12), (case, key)
            assert float(rows[case][f"{key}_median"]) == pytest.approx(value, rel=1e-12), (case, key)
    md = open(results / "smoke" / "table.md").read()
    assert "| `room_s1.default.gt_boxes` | 2/2 |" in md and "Measured " in md
    for group in ("room_s1", "room_s2"):
        page = results / "smoke" / "compare" / f"{group}.html"
        assert page.stat().st_size > 10000


def test_the_slurm_profile_submits_each_run_with_its_resources(tmp_path):
    # The shipped Slurm profile through Snakemake's own Slurm executor, against stand-in sbatch / sacct /
    # srun commands (tests/workflow/fake_slurm) that run each job on this machine: the smoke matrix in
    # timing mode, so the profile's threads and --exclusive for timing runs apply.
    fake = os.path.join(SOURCE, "tests", "workflow", "fake_slurm")
    env = dict(ENV, PATH=fake + os.pathsep + ENV.get("PATH", ""), FAKE_SLURM_DIR=str(tmp_path / "slurm"),
               FAKE_SLURM_ACCOUNT="lab", USER=ENV.get("USER") or "crowdslam")
    r = snakemake(tmp_path, smoke_matrix(), "--profile", os.path.join(SOURCE, "workflows", "profiles", "slurm"),
                  "--default-resources", "slurm_account=lab", "slurm_partition=cpu",
                  "mem_mb=1024", "runtime=30", "--max-status-checks-per-second", "1", config=["mode=timing"], env=env, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    # Each submission's sbatch options (the --wrap command after them repeats the profile's settings).
    calls = [c.split(" --wrap=")[0] + " " for c in open(tmp_path / "slurm" / "sbatch.log").read().splitlines()]
    runs = [c for c in calls if c.startswith("-J snakejob_run_timing_")]
    synth = [c for c in calls if c.startswith("-J snakejob_synth_")]
    assert len(runs) == 8 and len(synth) == 2 and len(calls) == 10, calls  # tables and pages stay local
    for c in runs:
        assert " -A lab -p cpu " in c and " --mem 256 " in c and " --cpus-per-task=3 --exclusive " in c, c
    for c in synth:
        assert " --cpus-per-task=1 " in c and "--exclusive" not in c, c
    table = json.load(open(tmp_path / "results" / "smoke" / "table.json"))
    assert table["matrix"]["mode"] == "timing"
    assert sorted(c["complete"] for c in table["cases"].values()) == [2, 2, 2, 2]
    for name in table["cases"]:
        for run in (1, 2):
            doc = json.load(open(tmp_path / "results" / "smoke" / name / str(run) / "run.json"))
            assert doc["mode"] == "threaded" and doc["end_state"] == "completed"


def test_interrupted_job_leaves_no_result(tmp_path):
    # A wrapper around crowdslam that, for one run, hangs after crowdslam has finished: the job is killed
    # with a complete run.json in its staging directory, the most tempting partial result there is.
    hang = "room_s2.default.no_filter/2.tmp-"
    flag = tmp_path / "reached"
    wrapper = tmp_path / "crowdslam-wrapper"
    wrapper.write_text(f"""#!/usr/bin/env bash
"{CLI}" "$@" || exit $?
if [[ -n "${{HANG_AT:-}}" && "$*" == *"$HANG_AT"* ]]; then touch "{flag}"; exec sleep 120; fi
""")
    wrapper.chmod(0o755)
    cmd = [SNAKEMAKE, "-s", SNAKEFILE, "--directory", str(tmp_path), "--configfile", smoke_matrix(),
           "--config", f"results={tmp_path}/results", f"crowdslam={wrapper}", "--cores", "1"]
    p = subprocess.Popen(cmd, env=dict(ENV, HANG_AT=hang), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True)
    deadline = time.monotonic() + 120
    while not flag.exists() and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.1)
    assert flag.exists(), "the job to interrupt never ran"
    os.killpg(p.pid, signal.SIGKILL)  # snakemake, the job script, the wrapper: all at once
    p.wait()
    smoke = tmp_path / "results" / "smoke"
    case = smoke / "room_s2.default.no_filter"
    staging = glob.glob(str(case / "2.tmp-*"))
    assert staging and json.load(open(os.path.join(staging[0], "out", "run.json")))["end_state"] == "completed"
    assert not (case / "2").exists()
    finished = {d: open(os.path.join(d, "job.json")).read() for d in glob.glob(str(smoke / "*.*.*" / "[0-9]"))}
    # What aggregation counts now: only the finished runs, none from the staging directory.
    r = subprocess.run([sys.executable, os.path.join(SOURCE, "workflows", "scripts", "aggregate.py"), "--matrix",
                        str(smoke / "matrix.json"), "--results", str(smoke), "--out", str(tmp_path / "partial")],
                       env=ENV, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    partial = json.load(open(tmp_path / "partial.json"))
    counted = [run["dir"] for c in partial["cases"].values() for run in c["runs"]]
    assert len(counted) == len(finished) and not any(".tmp-" in d for d in counted)
    assert partial["cases"]["room_s2.default.no_filter"]["complete"] <= 1
    # A rerun (after the lock the killed snakemake left) completes it and redoes nothing else.
    subprocess.run(cmd + ["--unlock"], env=ENV, capture_output=True, check=True)
    r = subprocess.run(cmd + ["--rerun-incomplete"], env=ENV, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (case / "2" / "job.json").exists() and not glob.glob(str(case / "2.tmp-*"))
    for d, text in finished.items():
        assert open(os.path.join(d, "job.json")).read() == text, f"{d} was run again"
    table = json.load(open(smoke / "table.json"))
    assert all(c["complete"] == 2 for c in table["cases"].values())
    assert aggregate.run_figures(str(case / "2")) is not None


def test_stale_staging_directories_of_dead_and_zombie_jobs_are_removed(tmp_path):
    """run_job.remove_stale keeps the staging directory of a job that runs, and removes those of jobs
    that are gone or are zombies (killed, not yet reaped: a killed snakemake's orphaned job waits for
    init to reap it, which made the rerun of test_interrupted_job_leaves_no_result keep it)."""
    import run_job  # noqa: E402 (workflows/scripts is on sys.path)
    final = tmp_path / "case" / "2"
    final.parent.mkdir()
    live = subprocess.Popen(["sleep", "30"])
    zombie = subprocess.Popen(["true"])
    try:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:  # `true` has exited, and nobody has reaped it
            with open(f"/proc/{zombie.pid}/stat") as f:
                if f.read().rsplit(")", 1)[1].split()[0] == "Z":
                    break
            time.sleep(0.01)
        gone = subprocess.Popen(["true"])
        gone.wait()  # exited and reaped: its pid runs nothing (unless reused at once)
        for pid in (live.pid, zombie.pid, gone.pid):
            (tmp_path / "case" / f"2.tmp-{pid}").mkdir()
        (tmp_path / "case" / "2.tmp-notapid").mkdir()
        run_job.remove_stale(str(final))
        left = sorted(p.name for p in (tmp_path / "case").iterdir())
        assert left == [f"2.tmp-{live.pid}"]
    finally:
        live.kill()
        live.wait()
        zombie.wait()
