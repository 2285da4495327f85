// fcl_poses: FCL 0.7's collide() timed on the same poses fitup checks (tests/bench/omplapp.rs,
// FITUP_CHECKS). Build (Debian libfcl-dev libccd-dev libeigen3-dev):
//   g++ -O3 -march=native -DNDEBUG -std=c++17 fcl_poses.cpp -o fcl_poses -I/usr/include/eigen3 -lfcl -lccd
// Usage: fcl_poses ENV.stl ROBOT.stl POSES.txt   (a pose a line: x y z qw qx qy qz)
// Prints: FCL poses=N colliding=K ns_per_check=T, the best of 5 passes over all poses; then one
// 0/1 verdict a line (1 = colliding), for the agreement count.
#include <fcl/fcl.h>
#include <Eigen/Geometry>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

using Model = fcl::BVHModel<fcl::OBBRSSd>;

static std::shared_ptr<Model> load(const char *path)
{
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    std::string d = ss.str();
    if (d.size() < 84) { std::cerr << "short STL " << path << "\n"; std::exit(1); }
    uint32_t n;
    std::memcpy(&n, d.data() + 80, 4);
    if (d.size() < 84 + 50ull * n) { std::cerr << "truncated STL " << path << "\n"; std::exit(1); }
    std::vector<fcl::Vector3d> v;
    std::vector<fcl::Triangle> t;
    for (uint32_t i = 0; i < n; ++i)
    {
        const char *r = d.data() + 84 + 50ull * i + 12;
        for (int j = 0; j < 3; ++j)
        {
            float xyz[3];
            std::memcpy(xyz, r + 12 * j, 12);
            v.emplace_back(xyz[0], xyz[1], xyz[2]);
        }
        t.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
    }
    auto m = std::make_shared<Model>();
    m->beginModel();
    m->addSubModel(v, t);
    m->endModel();
    return m;
}

int main(int argc, char **argv)
{
    if (argc < 4) { std::cerr << "usage: fcl_poses ENV.stl ROBOT.stl POSES.txt\n"; return 1; }
    fcl::CollisionObjectd env(load(argv[1]), fcl::Transform3d::Identity());
    fcl::CollisionObjectd rob(load(argv[2]), fcl::Transform3d::Identity());
    env.computeAABB();
    std::vector<fcl::Transform3d> poses;
    std::ifstream in(argv[3]);
    double x, y, z, w, i, j, k;
    while (in >> x >> y >> z >> w >> i >> j >> k)
    {
        fcl::Transform3d tf = fcl::Transform3d::Identity();
        tf.linear() = Eigen::Quaterniond(w, i, j, k).normalized().toRotationMatrix();
        tf.translation() = Eigen::Vector3d(x, y, z);
        poses.push_back(tf);
    }
    std::vector<int> hit(poses.size());
    double best = 1e300;
    for (int pass = 0; pass < 5; ++pass)
    {
        auto t0 = std::chrono::steady_clock::now();
        for (size_t p = 0; p < poses.size(); ++p)
        {
            // What OMPL's validity checker does per state: place, refit the box, collide.
            rob.setTransform(poses[p]);
            rob.computeAABB();
            fcl::CollisionRequestd req;
            fcl::CollisionResultd res;
            hit[p] = fcl::collide(&rob, &env, req, res) != 0;
        }
        double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (s < best) best = s;
    }
    size_t colliding = 0;
    for (int h : hit) colliding += h;
    std::printf("FCL poses=%zu colliding=%zu ns_per_check=%.1f\n", poses.size(), colliding, 1e9 * best / poses.size());
    for (int h : hit) std::printf("%d\n", h);
    return 0;
}
