#!/usr/bin/python3
"""Per-stage CPU account of one `crowdslam run`, in instructions (callgrind), which a noisy machine does
not change: decoding, pyramid, FAST, distribution, orientation, blur, descriptors, the detector, the people
filter, tracking, each local-mapping step, loop detection, the journal.

  scripts/profile_stages.py [--bin BUILD/apps/crowdslam/crowdslam] [--out out/profile] [--frames N]
                            [--keep] -- RUN_ARGS...
  scripts/profile_stages.py --annotate out/profile/callgrind.out      (account of an existing profile)

RUN_ARGS go to `crowdslam run` (e.g. --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml).
The run is `--sequential` (mapping inline after each frame, loop detection in the same order every time)
under `valgrind --tool=callgrind`, about 60 times slower than native: a whole bonn_crowd run takes about
25 minutes on one core. Writes OUT/callgrind.out, OUT/stages.json and OUT/stages.md (the table in
docs/PROFILE.md), and prints the table.

Each stage is the inclusive cost of the functions that do it (C++ names as callgrind_annotate prints
them, matched by the patterns below). A nested stage (FAST inside extraction) is shown inside its parent
and subtracted from the parent's "other" line, so the top-level stages add up to the whole run. What no
stage names is the "rest" line (start-up, vocabulary load, thread plumbing, the report).
"""
import argparse
import json
import os
import re
import subprocess
import sys

# (key, label, parent, functions): each pattern names one function (its demangled name without the argument
# list); a stage's cost is the sum of its functions' inclusive costs, so they must not call one another.
STAGES = [
    ("decode", "decoding (colour JPEG, depth PNG)", None,
     [r"crowdslam::io::decode_jpeg$", r"crowdslam::io::decode_png$"]),
    ("gray", "colour to gray", None, [r"crowdslam::feature::to_gray$"]),
    # prepare() is the reader thread's part of a frame's extraction (System::prepare); extract() finishes it
    # on the tracking thread. A frame that was not prepared (stereo with rectification) runs prepare()
    # inside extract(), and is then counted twice: profile RGB-D or monocular runs.
    ("extract", "ORB extraction", None,
     [r"crowdslam::feature::ORBExtractor::extract$", r"crowdslam::feature::ORBExtractor::prepare$"]),
    ("pyramid", "pyramid", "extract", [r"crowdslam::feature::ORBExtractor::build_pyramid$"]),
    ("fast", "FAST (grid, fallback threshold)", "extract", [r"crowdslam::feature::ORBExtractor::detect_fast_grid$"]),
    ("distribute", "quadtree distribution", "extract", [r"crowdslam::feature::QuadtreeDistributor::distribute$"]),
    ("orientation", "orientation (intensity centroid)", "extract", [r"crowdslam::feature::intensity_centroid_angle$"]),
    ("blur", "Gaussian blur", "extract", [r"cv::GaussianBlur$"]),
    ("descriptors", "steered BRIEF", "extract", [r"crowdslam::feature::steered_brief$"]),
    ("stereo", "stereo matching", None, [r"crowdslam::tracking::FrameBuilder::match_stereo$"]),
    ("assemble", "frame assembly (undistortion, depth, grid, bag of words)", None,
     [r"crowdslam::tracking::FrameBuilder::assemble$", r"crowdslam::tracking::FrameBuilder::assemble_stereo$"]),
    ("bow", "bag of words of the frame", "assemble", [r"crowdslam::tracking::FrameBuilder::finish_features$"]),
    ("detector", "person detector (OpenCV DNN)", None, [r"crowdslam::people::DnnDetector::detect$"]),
    ("people", "people stage (boxes, flat-box test, filter, budget)", None,
     [r"crowdslam::people::PeopleStage::filter$", r"crowdslam::people::PeopleStage::begin_frame$"]),
    ("tracking", "tracking (Tracker::track)", None, [r"crowdslam::tracking::Tracker::track$"]),
    ("dynamic", "geometric dynamic check", "tracking",
     [r"crowdslam::tracking::DynamicCheck::" + f + "$" for f in
      ("inherit", "screen", "update", "free_space", "trusted_inliers")]),
    ("local_map", "local map search and pose", "tracking", [r"crowdslam::tracking::Tracker::track_local_map$"]),
    ("mapping", "local mapping (LocalMapper::process_keyframe)", None,
     [r"crowdslam::mapping::LocalMapper::process_keyframe$"]),
    ("map_register", "register keyframe", "mapping", [r"crowdslam::mapping::LocalMapper::register_keyframe$"]),
    ("map_cull_points", "cull recent points", "mapping", [r"crowdslam::mapping::LocalMapper::cull_recent_points$"]),
    ("map_triangulate", "triangulate", "mapping", [r"crowdslam::mapping::LocalMapper::create_new_points$"]),
    ("map_fuse", "fuse with neighbours", "mapping", [r"crowdslam::mapping::LocalMapper::fuse_with_neighbours$"]),
    ("map_ba", "local bundle adjustment", "mapping", [r"crowdslam::mapping::LocalMapper::run_local_bundle_adjustment$"]),
    ("map_cull_kf", "cull keyframes", "mapping", [r"crowdslam::mapping::LocalMapper::cull_keyframes$"]),
    ("loop", "loop closing (detection, Sim3, correction)", None, [r"crowdslam::loop::LoopCloser::process_keyframe$"]),
    ("loop_detect", "loop detection", "loop", [r"crowdslam::loop::LoopDetector::detect$"]),
    ("journal", "journal (trajectory records, saved frames)", None,
     [r"crowdslam::journal::RunJournal::on_frame$", r"crowdslam::journal::JournalWriter::run$"]),
]

LINE = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+[^\s:]+:(.+?)(?:\s+\[[^\]]*\])?\s*$")
TOTAL = re.compile(r"^\s*([\d,]+)\s+\(100\.0%\)\s+PROGRAM TOTALS")


def bare_name(function):
    """`ns::Class::f(int) const` -> `ns::Class::f`, keeping template arguments of the scope."""
    depth = 0
    for i, c in enumerate(function):
        if c == "<":
            depth += 1
        elif c == ">":
            depth -= 1
        elif c == "(" and depth == 0 and i > 0:
            return function[:i]
    return function


def read_inclusive(path):
    out = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                         check=True, capture_output=True, text=True).stdout
    total, costs = None, {}
    for line in out.splitlines():
        m = TOTAL.match(line)
        if m:
            total = int(m.group(1).replace(",", ""))
            continue
        m = LINE.match(line)
        if not m:
            continue
        name = bare_name(m.group(2))
        costs[name] = max(costs.get(name, 0), int(m.group(1).replace(",", "")))
    if total is None:
        sys.exit(f"profile_stages: no PROGRAM TOTALS in callgrind_annotate output of {path}")
    return total, costs


def stage_costs(costs):
    """Inclusive cost per stage: the sum over its functions (each the function the pattern names)."""
    return {key: sum(cost for name, cost in costs.items() if any(re.fullmatch(p, name) for p in patterns))
            for key, _label, _parent, patterns in STAGES}


def account(path, frames):
    total, costs = read_inclusive(path)
    stage = stage_costs(costs)
    rows = []
    top_sum = 0
    for key, label, parent, _ in STAGES:
        if parent is None:
            top_sum += stage[key]
    for key, label, parent, _ in STAGES:
        if parent is not None:
            continue
        rows.append({"stage": key, "label": label, "level": 0, "instructions": stage[key]})
        children = [(k, lab) for k, lab, p, _ in STAGES if p == key]
        for ck, clabel in children:
            rows.append({"stage": ck, "label": clabel, "level": 1, "instructions": stage[ck]})
        if children:
            rest = stage[key] - sum(stage[ck] for ck, _ in children)
            rows.append({"stage": key + "_other", "label": "other", "level": 1, "instructions": max(rest, 0)})
    rows.append({"stage": "rest", "label": "rest (start-up, vocabulary, threads, report, ...)", "level": 0,
                 "instructions": max(total - top_sum, 0)})
    for r in rows:
        r["share"] = r["instructions"] / total if total else 0.0
        r["per_frame"] = r["instructions"] / frames if frames else None
    return {"total_instructions": total, "frames": frames, "stages": rows}


def markdown(acc):
    frames = acc["frames"]
    lines = ["| stage | instructions per frame (millions) | share of the run |", "| --- | ---: | ---: |"]
    for r in acc["stages"]:
        label = ("&nbsp;&nbsp;&nbsp;&nbsp;" if r["level"] else "") + r["label"]
        per = f"{r['per_frame'] / 1e6:.2f}" if frames else "-"
        lines.append(f"| {label} | {per} | {100 * r['share']:.1f} % |")
    total = acc["total_instructions"]
    per = f"{total / frames / 1e6:.2f}" if frames else "-"
    lines.append(f"| **whole run** | **{per}** | 100 % |")
    return "\n".join(lines) + "\n"


HWY_STUB = """// Valgrind 3.19 cannot run RDTSCP, which libhwy (loaded through OpenCV's image codecs) executes while
// it loads, to calibrate its timer; this stands in for that one function under the profiler.
#include <cstdint>
namespace hwy { namespace platform { uint64_t TimerResolution() { return 1; } } }
"""


def valgrind_env(binary, out):
    """The environment for valgrind: LD_PRELOAD of a stub for libhwy's timer when the binary loads libhwy."""
    env = dict(os.environ)
    ldd = subprocess.run(["ldd", binary], capture_output=True, text=True).stdout
    if "libhwy" not in ldd:
        return env
    source, script = os.path.join(out, "hwystub.cpp"), os.path.join(out, "hwystub.map")
    library = os.path.join(out, "libhwystub.so")
    with open(source, "w") as f:
        f.write(HWY_STUB)
    with open(script, "w") as f:
        f.write("HWY_0 { global: _ZN3hwy8platform15TimerResolutionEv; };\n")
    subprocess.run(["g++", "-O2", "-shared", "-fPIC", "-Wl,--version-script=" + script, source, "-o", library],
                   check=True)
    env["LD_PRELOAD"] = os.path.abspath(library)
    return env


def frames_of(run_dir):
    try:
        with open(os.path.join(run_dir, "run.json")) as f:
            return int(json.load(f)["summary"]["frames"])
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"profile_stages: cannot read the frame count from {run_dir}/run.json: {e}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bin", default="build/apps/crowdslam/crowdslam")
    parser.add_argument("--out", default="out/profile")
    parser.add_argument("--annotate", help="account of an existing callgrind.out (its run.json beside it)")
    parser.add_argument("run_args", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    if args.annotate:
        out = os.path.dirname(os.path.abspath(args.annotate))
        profile = args.annotate
    else:
        run_args = [a for a in args.run_args if a != "--"]
        if not run_args:
            parser.error("give RUN_ARGS after --, e.g. -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml")
        out = args.out
        os.makedirs(out, exist_ok=True)
        profile = os.path.join(out, "callgrind.out")
        run_dir = os.path.join(out, "run")
        command = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + profile,
                   args.bin, "run", "--sequential", "--overwrite", "--out", run_dir] + run_args
        print("profile_stages:", " ".join(command), file=sys.stderr, flush=True)
        subprocess.run(command, check=True, env=valgrind_env(args.bin, out))
    acc = account(profile, frames_of(os.path.join(out, "run")))
    with open(os.path.join(out, "stages.json"), "w") as f:
        json.dump(acc, f, indent=1)
    table = markdown(acc)
    with open(os.path.join(out, "stages.md"), "w") as f:
        f.write(table)
    print(table, end="")


if __name__ == "__main__":
    main()
