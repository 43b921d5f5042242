#!/usr/bin/python3
"""Check a saved map (crowdslam run --save-map MAP.db) against a dataset's ground-truth camera poses.

    scripts/map_vs_groundtruth.py MAP.db DATASET [--write-groundtruth-map OUT.db]

DATASET is a KITTI folder (poses.txt, times.txt) or a TUM/Bonn folder (groundtruth.txt). Keyframes are
matched to ground-truth poses by timestamp (within 0.02 s); the camera comes from the map's metadata.

1. Data association: every map point seen by two or more matched keyframes is triangulated from the
   ground-truth poses alone (least squares over all its rays, then Gauss-Newton on the reprojection error),
   and each observation's reprojection error under those poses is reported, by the point's ground-truth
   parallax. A false match (a keypoint that is not the point) shows up as a large error.
2. Depth: the map's point, moved into the ground-truth frame by the Sim(3) that aligns the keyframe centres,
   against that triangulated point: est/gt ratio of the distance from the first observing camera, by the
   frame where the point was first seen and by parallax. A ratio that changes with the frame and not with
   the parallax is scale drift, not biased triangulation.
3. --write-groundtruth-map OUT.db: a copy of the map whose keyframe poses are the ground truth (moved into
   the map's frame and scale by the inverse of that Sim(3)) and whose points are the triangulated ones.
   `crowdslam map optimise OUT.db --out OPT.db` then shows where the map's measurements alone lead from
   the true poses (docs/MAPPING.md "How to measure").
Exit 1 with a message for a missing or malformed input.
"""
import argparse
import os
import shutil
import sqlite3
import sys

import numpy as np

KEYPOINT_RECORD = 11  # 9 float32 + 2 int32 per keypoint (mapdb/map_writer.cpp)


def fail(message):
    print(f"error: {message}", file=sys.stderr)
    sys.exit(1)


def quat_to_matrix(qx, qy, qz, qw):
    n = np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    x, y, z, w = qx / n, qy / n, qz / n, qw / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(r):
    w = np.sqrt(max(0.0, 1 + r[0, 0] + r[1, 1] + r[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    q = np.array([x, y, z, w])
    return q / np.linalg.norm(q)


def read_numbers(path, fields):
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            text = line.strip()
            if not text or text.startswith('#'):
                continue
            try:
                values = [float(v) for v in text.replace(',', ' ').split()]
            except ValueError:
                fail(f"{path}:{number}: not numbers")
            if len(values) < fields:
                fail(f"{path}:{number}: expected {fields} fields, got {len(values)}")
            rows.append(values[:fields])
    return rows


def ground_truth(dataset):
    """(timestamps, world_from_cam 4x4 list) of a KITTI or TUM dataset folder."""
    poses, times, gt_tum = (os.path.join(dataset, n) for n in ('poses.txt', 'times.txt', 'groundtruth.txt'))
    out = []
    if os.path.isfile(poses) and os.path.isfile(times):
        stamps = [r[0] for r in read_numbers(times, 1)]
        rows = read_numbers(poses, 12)
        if len(rows) != len(stamps):
            fail(f"{poses}: {len(rows)} poses but {len(stamps)} timestamps in {times}")
        for s, r in zip(stamps, rows):
            t = np.eye(4)
            t[:3, :4] = np.array(r).reshape(3, 4)
            out.append((s, t))
    elif os.path.isfile(gt_tum):
        for r in read_numbers(gt_tum, 8):
            t = np.eye(4)
            t[:3, :3] = quat_to_matrix(r[4], r[5], r[6], r[7])
            t[:3, 3] = r[1:4]
            out.append((r[0], t))
    else:
        fail(f"{dataset}: no ground truth (KITTI poses.txt + times.txt, or TUM groundtruth.txt)")
    return np.array([s for s, _ in out]), [t for _, t in out]


def read_map(path):
    if not os.path.isfile(path):
        fail(f"{path}: no such map file")
    try:
        db = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        meta = dict(db.execute('SELECT key, value FROM metadata'))
        camera = {k: float(meta[f'camera.{k}']) for k in ('fx', 'fy', 'cx', 'cy')}
        keyframes = {}
        for (kid, stamp, qx, qy, qz, qw, tx, ty, tz, blob) in db.execute(
                'SELECT id, timestamp, qx, qy, qz, qw, tx, ty, tz, keypoints FROM keyframes'):
            n = len(blob) // (4 * KEYPOINT_RECORD)
            floats = np.frombuffer(blob, dtype=np.float32).reshape(n, KEYPOINT_RECORD)
            ints = np.frombuffer(blob, dtype=np.int32).reshape(n, KEYPOINT_RECORD)
            keyframes[kid] = dict(stamp=stamp, uv=floats[:, 2:4].astype(float), octave=ints[:, 9],
                                  R=quat_to_matrix(qx, qy, qz, qw), t=np.array([tx, ty, tz]))
        points = {pid: np.array([x, y, z]) for pid, x, y, z in db.execute('SELECT id, x, y, z FROM map_points')}
        observations = {}
        for pid, kid, index in db.execute('SELECT point_id, keyframe_id, keypoint_index FROM observations'):
            observations.setdefault(pid, []).append((kid, index))
        scale_factor = float(meta.get('orb.scale_factor', 1.2))
        db.close()
    except (sqlite3.Error, KeyError, ValueError) as e:
        fail(f"{path}: not a crowdslam map ({e})")
    return camera, scale_factor, keyframes, points, observations


def sim3(source, target):
    """s, R, t with target ~ s R source + t (Umeyama)."""
    ms, mt = source.mean(0), target.mean(0)
    x, y = source - ms, target - mt
    u, d, vt = np.linalg.svd(y.T @ x / len(source))
    e = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        e[2, 2] = -1
    r = u @ e @ vt
    s = np.trace(np.diag(d) @ e) / (x ** 2).sum(1).mean()
    return s, r, mt - s * r @ ms


def triangulate(cams, camera):
    """Point from (R_wc, c_w, u, v, sigma) rays: linear least squares, then Gauss-Newton on pixels."""
    fx, fy, cx, cy = camera['fx'], camera['fy'], camera['cx'], camera['cy']
    a, b = np.zeros((3, 3)), np.zeros(3)
    rays = []
    for r_wc, c_w, u, v, _ in cams:
        d = r_wc @ np.array([(u - cx) / fx, (v - cy) / fy, 1.0])
        d /= np.linalg.norm(d)
        rays.append(d)
        p = np.eye(3) - np.outer(d, d)
        a += p
        b += p @ c_w
    x = np.linalg.lstsq(a, b, rcond=None)[0]
    for _ in range(5):
        h, g = np.zeros((3, 3)), np.zeros(3)
        for r_wc, c_w, u, v, sigma in cams:
            pc = r_wc.T @ (x - c_w)
            if pc[2] <= 0:
                continue
            res = np.array([fx * pc[0] / pc[2] + cx - u, fy * pc[1] / pc[2] + cy - v]) / sigma
            j = np.array([[fx / pc[2], 0, -fx * pc[0] / pc[2] ** 2],
                          [0, fy / pc[2], -fy * pc[1] / pc[2] ** 2]]) @ r_wc.T / sigma
            h += j.T @ j
            g += j.T @ res
        try:
            x = x - np.linalg.solve(h + 1e-9 * np.eye(3), g)
        except np.linalg.LinAlgError:
            break
    errors = []
    for r_wc, c_w, u, v, sigma in cams:
        pc = r_wc.T @ (x - c_w)
        errors.append(np.inf if pc[2] <= 0 else
                      np.hypot(fx * pc[0] / pc[2] + cx - u, fy * pc[1] / pc[2] + cy - v) / sigma)
    cos_min = min(float(np.dot(p, q)) for i, p in enumerate(rays) for q in rays[i + 1:])
    return x, errors, np.degrees(np.arccos(np.clip(cos_min, -1, 1)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('map')
    parser.add_argument('dataset')
    parser.add_argument('--write-groundtruth-map', metavar='OUT.db')
    args = parser.parse_args()

    camera, scale_factor, keyframes, points, observations = read_map(args.map)
    stamps, poses = ground_truth(args.dataset)
    gt_of = {}
    for kid, kf in keyframes.items():
        i = int(np.argmin(np.abs(stamps - kf['stamp'])))
        if abs(stamps[i] - kf['stamp']) <= 0.02:
            gt_of[kid] = poses[i]
    skipped = len(keyframes) - len(gt_of)
    if len(gt_of) < 3:
        fail(f"{args.map}: only {len(gt_of)} keyframes have a ground-truth pose within 0.02 s")
    if skipped:
        print(f"warning: {skipped} keyframes have no ground-truth pose within 0.02 s and are left out",
              file=sys.stderr)
    ids = sorted(gt_of)
    first_frame = {kid: int(np.argmin(np.abs(stamps - keyframes[kid]['stamp']))) for kid in ids}
    centres = np.array([-keyframes[k]['R'].T @ keyframes[k]['t'] for k in ids])
    s, r, t = sim3(centres, np.array([gt_of[k][:3, 3] for k in ids]))

    rows, triangulated = [], {}
    for pid, obs in observations.items():
        obs = [(k, i) for k, i in obs if k in gt_of]
        if len(obs) < 2 or pid not in points:
            continue
        cams = [(gt_of[k][:3, :3], gt_of[k][:3, 3], *keyframes[k]['uv'][i],
                 scale_factor ** keyframes[k]['octave'][i]) for k, i in obs]
        x, errors, parallax = triangulate(cams, camera)
        triangulated[pid] = x
        c0 = gt_of[obs[0][0]][:3, 3]
        estimate = s * r @ points[pid] + t
        ratio = np.linalg.norm(estimate - c0) / max(np.linalg.norm(x - c0), 1e-12)
        rows.append((parallax, max(errors), ratio, min(first_frame[k] for k, _ in obs)))
    if not rows:
        fail(f"{args.map}: no map point is seen by two keyframes with ground truth")
    rows = np.array(rows)
    good = np.isfinite(rows[:, 1]) & (rows[:, 1] < 3)
    print(f"map {args.map}: {len(keyframes)} keyframes ({len(gt_of)} with ground truth), "
          f"{len(rows)} points seen twice or more")
    print(f"keyframe centres to ground truth: Sim(3) scale {s:.4f}")
    print("\n1. observations under the ground-truth poses (error / sigma of the keypoint's level)")
    print("   gt parallax      points   worst error median   > 3 sigma   > 6 sigma")
    bins = [(0, 1), (1, 2), (2, 3.1), (3.1, 6), (6, 180)]
    for lo, hi in bins:
        m = (rows[:, 0] >= lo) & (rows[:, 0] < hi)
        if m.any():
            e = rows[m, 1]
            print(f"   {lo:4.1f}-{hi:5.1f} deg   {m.sum():7d}   {np.median(e):17.2f}   {100 * (e > 3).mean():8.1f} %"
                  f"   {100 * (e > 6).mean():8.1f} %")
    print("\n2. est/gt distance from the first observing camera, median (points consistent with the ground "
          "truth), by first frame and gt parallax")
    print("   first frames   " + "".join(f"{f'{lo}-{hi} deg':>16}" for lo, hi in [(0, 2), (2, 3.1), (3.1, 6), (6, 180)]))
    last = int(rows[:, 3].max())
    span = max(10, (last + 1) // 10)
    for f0 in range(0, last + 1, span):
        line = f"   {f0:5d}-{f0 + span - 1:<6d} "
        for lo, hi in [(0, 2), (2, 3.1), (3.1, 6), (6, 180)]:
            m = good & (rows[:, 3] >= f0) & (rows[:, 3] < f0 + span) & (rows[:, 0] >= lo) & (rows[:, 0] < hi)
            line += f"{np.median(rows[m, 2]):9.3f} ({m.sum():4d})" if m.any() else f"{'-':>16}"
        print(line)

    if args.write_groundtruth_map:
        out = args.write_groundtruth_map
        if os.path.exists(out):
            fail(f"{out}: exists; choose another file")
        tmp = f"{out}.tmp.{os.getpid()}"
        shutil.copyfile(args.map, tmp)
        db = sqlite3.connect(tmp)
        with db:
            for kid in ids:  # world_from_cam in map units: x_map = R^T (x_gt - t) / s
                g = gt_of[kid]
                r_wc = r.T @ g[:3, :3]
                c = r.T @ (g[:3, 3] - t) / s
                r_cw = r_wc.T
                q = matrix_to_quat(r_cw)
                tcw = -r_cw @ c
                db.execute('UPDATE keyframes SET qx=?, qy=?, qz=?, qw=?, tx=?, ty=?, tz=? WHERE id=?',
                           (*map(float, q), *map(float, tcw), kid))
            for pid, x in triangulated.items():
                m = r.T @ (x - t) / s
                db.execute('UPDATE map_points SET x=?, y=?, z=? WHERE id=?', (*map(float, m), pid))
        db.close()
        os.replace(tmp, out)
        print(f"\nwritten {out}: {len(ids)} keyframes at their ground-truth poses, {len(triangulated)} points "
              f"triangulated from them (map frame and scale)")


if __name__ == '__main__':
    main()
