#!/usr/bin/env python3
"""OMPL peer of `cargo bench --bench planning`: the same problem (STL meshes, bounds,
start, goal exported by the Rust bench as problem.json), planned with OMPL's
RRTConnect or RRT over SE(3), validity by FCL mesh collision (BVH, OBBRSS).

Usage: ompl_peer.py PROBLEM_JSON PLANNER RUNS TIME_LIMIT_S
Prints one JSON object: {"planner", "runs", "solved", "times_s": [...]}.
A run that finds no exact solution within the time limit counts as failed.
Motion validation: OMPL's discrete checker at `resolution_mm` of the SE(3)
metric (translation mm + rotation_weight * angle), as stated in the JSON.
"""
import json
import sys
import time

import fcl
import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou


def read_stl(path):
    """Binary STL -> (vertices (n*3, 3), triangles (n, 3))."""
    data = open(path, "rb").read()
    n = int.from_bytes(data[80:84], "little")
    rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                        count=n, offset=84)
    verts = rec["v"].reshape(-1, 3).astype(np.float64)
    tris = np.arange(3 * n, dtype=np.int64).reshape(-1, 3)
    return verts, tris


def bvh(path):
    v, t = read_stl(path)
    m = fcl.BVHModel()
    m.beginModel(len(v), len(t))
    m.addSubModel(v, t)
    m.endModel()
    return m


def main():
    spec_path, planner_name, runs, limit = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
    spec = json.load(open(spec_path))
    base = spec_path.rsplit("/", 1)[0]
    moving = fcl.CollisionObject(bvh(f"{base}/{spec['moving_stl']}"), fcl.Transform())
    # obstacles are exported already in world coordinates
    obstacles = [fcl.CollisionObject(bvh(f"{base}/{s}"), fcl.Transform()) for s in spec["obstacle_stls"]]
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(obstacles)
    manager.setup()
    request = fcl.CollisionRequest()

    ou.setLogLevel(ou.LogLevel.LOG_ERROR)
    space = ob.SE3StateSpace()
    bounds = ob.RealVectorBounds(3)
    for i in range(3):
        bounds.setLow(i, spec["bounds_min"][i])
        bounds.setHigh(i, spec["bounds_max"][i])
    space.setBounds(bounds)
    # same metric as fitup: |dt| + rotation_weight * angle
    space.setSubspaceWeight(1, spec["rotation_weight_mm_per_rad"])

    def valid(state):
        r = state.rotation()
        tf = fcl.Transform(np.array([r.w, r.x, r.y, r.z]), np.array([state.getX(), state.getY(), state.getZ()]))
        moving.setTransform(tf)
        data = fcl.CollisionData(request=request)
        manager.collide(moving, data, fcl.defaultCollisionCallback)
        return not data.result.is_collision

    lift = spec.get("peer_lift_mm", 0.0)

    def set_pose(state, pose):
        t, q = pose["t"], pose["q"]
        state.setXYZ(t[0], t[1], t[2] + lift)
        r = state.rotation()
        r.w, r.x, r.y, r.z = q

    times, solved = [], 0
    for run in range(runs):
        ss = og.SimpleSetup(space)
        ss.setStateValidityChecker(valid)
        si = ss.getSpaceInformation()
        si.setStateValidityCheckingResolution(spec["resolution_mm"] / space.getMaximumExtent())
        start, goal = space.allocState(), space.allocState()
        set_pose(start, spec["start"])
        set_pose(goal, spec["goal"])
        ss.setStartAndGoalStates(start, goal)
        if planner_name == "RRTConnect":
            p = og.RRTConnect(si)
        else:
            p = og.RRT(si)
        p.setRange(spec.get("range_mm", 10.0))
        ss.setPlanner(p)
        ou.RNG.setSeed(run + 1)
        t0 = time.perf_counter()
        status = ss.solve(limit)
        dt = time.perf_counter() - t0
        ok = bool(status) and ss.haveExactSolutionPath()
        solved += ok
        times.append(dt if ok else None)
    print(json.dumps({"planner": planner_name, "runs": runs, "solved": solved, "times_s": times}))


if __name__ == "__main__":
    main()
