#!/usr/bin/python3
"""Make a variant of a dataset: a later start, fewer frames, another rate (every k-th frame) or played
backwards. The variant is a new directory whose image lists (and ground truth) name the original images
through symbolic links, so nothing large is copied.

  scripts/make_variant.py SRC OUT [--start N] [--frames N] [--stride K] [--reverse]

TUM RGB-D layout (rgb.txt, depth.txt, groundtruth.txt): the selection applies to rgb.txt; depth and
ground-truth lines inside the selected time span are kept. Played backwards, every timestamp t becomes
t_first + t_last - t (images, depth and ground truth alike), so the associations stay as they were and
the time runs forward. KITTI layout (times.txt, image_0/ [image_1/], calib.txt, poses.txt): the selected
frames are renumbered 000000.png, ... with their times rewritten the same way.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


def read_list(path: Path) -> tuple[list[str], list[tuple[float, str]]]:
    header, rows = [], []
    for line in path.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            header.append(line)
            continue
        stamp, rest = line.split(maxsplit=1)
        rows.append((float(stamp), rest))
    return header, rows


def pick(n: int, start: int, frames: int, stride: int, reverse: bool) -> list[int]:
    if start >= n:
        sys.exit(f"make_variant: --start {start} is past the last frame ({n} frames)")
    indices = list(range(start, n))
    if reverse:
        indices.reverse()
    indices = indices[::stride]
    return indices[:frames] if frames > 0 else indices


def link(src: Path, dst: Path) -> None:
    dst.symlink_to(os.path.relpath(src.resolve(), dst.parent.resolve()))


def tum(src: Path, out: Path, args: argparse.Namespace) -> int:
    header, rgb = read_list(src / "rgb.txt")
    chosen = pick(len(rgb), args.start, args.frames, args.stride, args.reverse)
    stamps = [rgb[i][0] for i in chosen]
    lo, hi = min(stamps), max(stamps)
    margin = 0.05  # depth or ground truth up to 50 ms outside the span still associates with its end frames
    restamp = (lambda t: lo + hi - t) if args.reverse else (lambda t: t)
    keep = set(chosen)
    rows = sorted((restamp(t), f) for i, (t, f) in enumerate(rgb) if i in keep)
    write_list(out / "rgb.txt", header, rows)
    for name in ("depth.txt", "groundtruth.txt"):
        if not (src / name).exists():
            continue
        h, listed = read_list(src / name)
        span = [(restamp(t), rest) for t, rest in listed if lo - margin <= t <= hi + margin]
        write_list(out / name, h, sorted(span))
    for entry in src.iterdir():
        if entry.is_dir():
            link(entry, out / entry.name)
        elif entry.name not in ("rgb.txt", "depth.txt", "groundtruth.txt", "associations.txt"):
            link(entry, out / entry.name)
    return len(rows)


def write_list(path: Path, header: list[str], rows: list[tuple[float, str]]) -> None:
    with path.open("w") as f:
        for line in header:
            f.write(line + "\n")
        for t, rest in rows:
            f.write(f"{t:.6f} {rest}\n")


def kitti(src: Path, out: Path, args: argparse.Namespace) -> int:
    times = [float(line) for line in (src / "times.txt").read_text().split()]
    chosen = pick(len(times), args.start, args.frames, args.stride, args.reverse)
    stamps = [times[i] for i in chosen]
    lo, hi = min(stamps), max(stamps)
    restamp = (lambda t: lo + hi - t) if args.reverse else (lambda t: t)
    # Played backwards, the first output frame is the latest; its new time is lo, and times grow from there.
    poses = (src / "poses.txt").read_text().splitlines() if (src / "poses.txt").exists() else None
    with (out / "times.txt").open("w") as f:
        for i in chosen:
            f.write(f"{restamp(times[i]):.6e}\n")
    if poses is not None:
        (out / "poses.txt").write_text("".join(poses[i] + "\n" for i in chosen))
    for camera in ("image_0", "image_1", "image_2", "image_3"):
        if not (src / camera).is_dir():
            continue
        (out / camera).mkdir()
        for k, i in enumerate(chosen):
            link(src / camera / f"{i:06d}.png", out / camera / f"{k:06d}.png")
    for name in ("calib.txt",):
        if (src / name).exists():
            link(src / name, out / name)
    return len(chosen)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("src", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--start", type=int, default=0, help="first frame (of the original order)")
    parser.add_argument("--frames", type=int, default=0, help="at most this many frames (0 = all)")
    parser.add_argument("--stride", type=int, default=1, help="every k-th frame (k = 2 halves the rate)")
    parser.add_argument("--reverse", action="store_true", help="play the sequence backwards")
    args = parser.parse_args()
    if args.stride < 1 or args.start < 0 or args.frames < 0:
        sys.exit("make_variant: --stride must be >= 1, --start and --frames >= 0")
    if args.out.exists():
        sys.exit(f"make_variant: {args.out} exists")
    args.out.mkdir(parents=True)
    if (args.src / "rgb.txt").exists():
        n = tum(args.src, args.out, args)
    elif (args.src / "times.txt").exists():
        n = kitti(args.src, args.out, args)
    else:
        sys.exit(f"make_variant: {args.src}: neither a TUM (rgb.txt) nor a KITTI (times.txt) layout")
    print(f"{args.out}: {n} frames")


if __name__ == "__main__":
    main()
