// OMPL 1.5 C++ peer of `cargo bench --bench planning` (compiled by the bench when
// the Debian headers exist: libompl-dev, libfcl-dev). The same problem as fitup
// (binary STL meshes, bounds, start, goal, rotation weight) from the plain-text
// spec the bench writes (problem.txt, one `key values...` line each):
//   moving FILE | obstacle FILE (world coordinates) | bounds x0 y0 z0 x1 y1 z1
//   start x y z qw qx qy qz | goal ... | rotation_weight W | resolution_mm R | lift_mm L
// Usage: harness SPEC PLANNER(RRTConnect|KPIECE1|BiTRRT) RUNS TIME_LIMIT_S
// Prints {"planner": ..., "runs": n, "solved": k, "times_s": [t or null, ...]}.
// Validity: FCL mesh collision (BVH of OBBRSS); motion: OMPL's discrete checker at
// `resolution_mm` of the SE(3) metric (translation + rotation_weight * angle).
#include <ompl/base/spaces/SE3StateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/kpiece/KPIECE1.h>
#include <ompl/geometric/planners/rrt/BiTRRT.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <fcl/fcl.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace ob = ompl::base;
namespace og = ompl::geometric;
using Model = fcl::BVHModel<fcl::OBBRSSd>;

static std::shared_ptr<Model> read_stl(const std::string &path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error("cannot read " + path);
    char header[80];
    f.read(header, 80);
    uint32_t n = 0;
    f.read(reinterpret_cast<char *>(&n), 4);
    std::vector<fcl::Vector3d> v;
    std::vector<fcl::Triangle> t;
    for (uint32_t i = 0; i < n; ++i) {
        float r[12];
        uint16_t attr;
        f.read(reinterpret_cast<char *>(r), 48);
        f.read(reinterpret_cast<char *>(&attr), 2);
        for (int k = 0; k < 3; ++k) v.emplace_back(r[3 + 3 * k], r[4 + 3 * k], r[5 + 3 * k]);
        t.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
    }
    if (!f) throw std::runtime_error("truncated STL " + path);
    auto m = std::make_shared<Model>();
    m->beginModel();
    m->addSubModel(v, t);
    m->endModel();
    return m;
}

struct Pose {
    double t[3], q[4];
};

int main(int argc, char **argv) {
    if (argc != 5) {
        std::cerr << "usage: harness SPEC PLANNER RUNS TIME_LIMIT_S\n";
        return 2;
    }
    std::string spec_path = argv[1], planner = argv[2];
    int runs = std::stoi(argv[3]);
    double limit = std::stod(argv[4]);
    std::string dir = spec_path.substr(0, spec_path.find_last_of('/') + 1);
    std::ifstream spec(spec_path);
    std::string line;
    std::shared_ptr<Model> moving;
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> obstacles;
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, weight = 1.0, resolution = 0.05, lift = 0.0;
    Pose start{}, goal{};
    while (std::getline(spec, line)) {
        std::istringstream s(line);
        std::string key;
        s >> key;
        if (key == "moving") {
            std::string f;
            s >> f;
            moving = read_stl(dir + f);
        } else if (key == "obstacle") {
            std::string f;
            s >> f;
            obstacles.push_back(std::make_unique<fcl::CollisionObjectd>(read_stl(dir + f)));
        } else if (key == "bounds") {
            s >> lo[0] >> lo[1] >> lo[2] >> hi[0] >> hi[1] >> hi[2];
        } else if (key == "start" || key == "goal") {
            Pose &p = key == "start" ? start : goal;
            s >> p.t[0] >> p.t[1] >> p.t[2] >> p.q[0] >> p.q[1] >> p.q[2] >> p.q[3];
        } else if (key == "rotation_weight") {
            s >> weight;
        } else if (key == "resolution_mm") {
            s >> resolution;
        } else if (key == "lift_mm") {
            s >> lift;
        }
    }
    if (!moving) {
        std::cerr << spec_path << ": no moving mesh\n";
        return 2;
    }
    fcl::CollisionObjectd moving_obj(moving);
    fcl::DynamicAABBTreeCollisionManagerd manager;
    for (auto &o : obstacles) {
        o->computeAABB();
        manager.registerObject(o.get());
    }
    manager.setup();
    ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);

    auto space = std::make_shared<ob::SE3StateSpace>();
    ob::RealVectorBounds b(3);
    for (int i = 0; i < 3; ++i) {
        b.setLow(i, lo[i]);
        b.setHigh(i, hi[i]);
    }
    space->setBounds(b);
    space->setSubspaceWeight(1, weight);
    auto valid = [&](const ob::State *st) {
        const auto *s = st->as<ob::SE3StateSpace::StateType>();
        const auto &r = s->rotation();
        fcl::Transform3d tf = fcl::Transform3d::Identity();
        tf.linear() = fcl::Quaterniond(r.w, r.x, r.y, r.z).toRotationMatrix();
        tf.translation() = fcl::Vector3d(s->getX(), s->getY(), s->getZ());
        moving_obj.setTransform(tf);
        moving_obj.computeAABB();
        fcl::DefaultCollisionData<double> data;
        manager.collide(&moving_obj, &data, fcl::DefaultCollisionFunction<double>);
        return !data.result.isCollision();
    };
    auto set = [&](ob::ScopedState<ob::SE3StateSpace> &st, const Pose &p) {
        st->setXYZ(p.t[0], p.t[1], p.t[2] + lift);
        st->rotation().w = p.q[0];
        st->rotation().x = p.q[1];
        st->rotation().y = p.q[2];
        st->rotation().z = p.q[3];
    };
    std::vector<double> times;
    int solved = 0;
    for (int run = 0; run < runs; ++run) {
        ompl::RNG::setSeed(run + 1);
        og::SimpleSetup ss(space);
        ss.setStateValidityChecker(valid);
        auto si = ss.getSpaceInformation();
        si->setStateValidityCheckingResolution(resolution / space->getMaximumExtent());
        ob::ScopedState<ob::SE3StateSpace> s(space), g(space);
        set(s, start);
        set(g, goal);
        ss.setStartAndGoalStates(s, g);
        if (planner == "KPIECE1")
            ss.setPlanner(std::make_shared<og::KPIECE1>(si));
        else if (planner == "BiTRRT")
            ss.setPlanner(std::make_shared<og::BiTRRT>(si));
        else
            ss.setPlanner(std::make_shared<og::RRTConnect>(si));
        auto t0 = std::chrono::steady_clock::now();
        auto status = ss.solve(limit);
        double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        bool ok = bool(status) && ss.haveExactSolutionPath();
        solved += ok;
        times.push_back(ok ? dt : -1.0);
    }
    std::printf("{\"planner\": \"%s\", \"runs\": %d, \"solved\": %d, \"times_s\": [", planner.c_str(), runs, solved);
    for (size_t i = 0; i < times.size(); ++i) {
        if (i) std::printf(", ");
        if (times[i] < 0) std::printf("null");
        else std::printf("%.6f", times[i]);
    }
    std::printf("]}\n");
    return 0;
}
