"""Peer timing for `cargo bench --bench interference`: python-fcl and coal (OBBRSS)
collision queries on the same meshes and pose pairs as fitup.

Usage: interference_peers.py DIR  (DIR holds a.stl, b.stl, poses.txt)
poses.txt: lines "category tx ty tz qw qx qy qz  tx ty tz qw qx qy qz" (mm).
Prints one line per peer and category: "peer category us_per_query collisions".
The time of an empty Python loop over the same pairs is subtracted.
"""
import struct
import sys
import time

import numpy as np


def read_stl(path):
    data = open(path, "rb").read()
    n = struct.unpack_from("<I", data, 80)[0]
    tri = np.frombuffer(data, dtype=np.dtype([("n", "<3f4"), ("v", "<9f4"), ("a", "<u2")]),
                        count=n, offset=84)
    v = tri["v"].reshape(-1, 3).astype(np.float64)
    return v, np.arange(len(v)).reshape(-1, 3)


def quat_to_matrix(w, x, y, z):
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def load(dirname):
    a = read_stl(f"{dirname}/a.stl")
    b = read_stl(f"{dirname}/b.stl")
    cats = {}
    for line in open(f"{dirname}/poses.txt"):
        f = line.split()
        v = [float(x) for x in f[1:]]
        cats.setdefault(f[0], []).append((v[0:3], v[3:7], v[7:10], v[10:14]))
    return a, b, cats


def empty_loop(pairs, tfs):
    t0 = time.perf_counter()
    for ta, tb in tfs:
        pass
    return time.perf_counter() - t0


def run_fcl(a, b, cats):
    import fcl

    def model(m):
        bvh = fcl.BVHModel()
        bvh.beginModel(len(m[1]), len(m[0]))
        bvh.addSubModel(m[0], m[1])
        bvh.endModel()
        return bvh

    oa, ob = fcl.CollisionObject(model(a)), fcl.CollisionObject(model(b))
    req = fcl.CollisionRequest()
    for cat, pairs in cats.items():
        tfs = [(fcl.Transform(np.array(qa), np.array(ta)), fcl.Transform(np.array(qb), np.array(tb)))
               for ta, qa, tb, qb in pairs]
        hits = 0
        t0 = time.perf_counter()
        for ta, tb in tfs:
            oa.setTransform(ta)
            ob.setTransform(tb)
            res = fcl.CollisionResult()
            hits += fcl.collide(oa, ob, req, res) > 0
        dt = time.perf_counter() - t0 - empty_loop(pairs, tfs)
        print(f"fcl {cat} {dt / len(pairs) * 1e6:.3f} {hits}", flush=True)


def run_coal(a, b, cats):
    import coal

    def model(m):
        bvh = coal.BVHModelOBBRSS()
        bvh.beginModel(len(m[1]), len(m[0]))
        v = m[0]
        for t in m[1]:
            bvh.addTriangle(v[t[0]], v[t[1]], v[t[2]])
        bvh.endModel()
        return bvh

    ga, gb = model(a), model(b)
    req = coal.CollisionRequest()
    res = coal.CollisionResult()
    for cat, pairs in cats.items():
        tfs = [(coal.Transform3s(quat_to_matrix(*qa), np.array(ta)),
                coal.Transform3s(quat_to_matrix(*qb), np.array(tb))) for ta, qa, tb, qb in pairs]
        hits = 0
        t0 = time.perf_counter()
        for ta, tb in tfs:
            res.clear()
            hits += coal.collide(ga, ta, gb, tb, req, res) > 0
        dt = time.perf_counter() - t0 - empty_loop(pairs, tfs)
        print(f"coal {cat} {dt / len(pairs) * 1e6:.3f} {hits}", flush=True)


if __name__ == "__main__":
    a, b, cats = load(sys.argv[1])
    for run in (run_fcl, run_coal):
        try:
            run(a, b, cats)
        except Exception as e:  # a peer that fails to load must not hide the other
            print(f"# {run.__name__} failed: {e!r}", flush=True)
