// A command-line driver around Jeroen De Maeyer / Jonathan Meyer's C++ opw_kinematics
// (header-only, Eigen), written for fitup's benchmarks. opw_kinematics itself is never
// committed: its include folder is named by FITUP_OPW_KIN_SRC and compiled by
// tests/common/opw_kin.rs at bench time.
//
// argv: a1 a2 b c1 c2 c3 c4 (the OPW parameters, any length unit; zero offsets, no
// sign corrections). stdin, one request per line, poses row-major 4x4 of the flange:
//   fk q1 .. q6            -> 16 numbers
//   ik T00 .. T33          -> n, then n joint vectors (6 numbers each), one line
//   bench reps n T[16*n]   -> CPU ns per inverse() call over reps passes of the n
//                             targets, and the total number of valid solutions
#include <opw_kinematics/opw_kinematics.h>
#include <opw_kinematics/opw_utilities.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

static double cpu_ns() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e9 + t.tv_nsec;
}

static opw_kinematics::Transform<double> pose_of(const double* m) {
  opw_kinematics::Transform<double> t = opw_kinematics::Transform<double>::Identity();
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 4; c++) t.matrix()(r, c) = m[4 * r + c];
  return t;
}

int main(int argc, char** argv) {
  if (argc != 8) return 2;
  opw_kinematics::Parameters<double> p;
  p.a1 = std::atof(argv[1]);
  p.a2 = std::atof(argv[2]);
  p.b = std::atof(argv[3]);
  p.c1 = std::atof(argv[4]);
  p.c2 = std::atof(argv[5]);
  p.c3 = std::atof(argv[6]);
  p.c4 = std::atof(argv[7]);
  char mode[16];
  while (std::scanf("%15s", mode) == 1) {
    if (std::strcmp(mode, "fk") == 0) {
      std::array<double, 6> q;
      for (double& v : q) std::scanf("%lf", &v);
      auto t = opw_kinematics::forward(p, q);
      for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) std::printf("%.17g ", t.matrix()(r, c));
      std::printf("\n");
    } else if (std::strcmp(mode, "ik") == 0) {
      double m[16];
      for (double& v : m) std::scanf("%lf", &v);
      auto sols = opw_kinematics::inverse(p, pose_of(m));
      int n = 0;
      for (const auto& s : sols) n += opw_kinematics::isValid(s) ? 1 : 0;
      std::printf("%d", n);
      for (const auto& s : sols)
        if (opw_kinematics::isValid(s))
          for (double v : s) std::printf(" %.17g", v);
      std::printf("\n");
    } else if (std::strcmp(mode, "bench") == 0) {
      int reps = 0, n = 0;
      std::scanf("%d %d", &reps, &n);
      std::vector<opw_kinematics::Transform<double>> poses;
      poses.reserve(static_cast<size_t>(n));
      for (int i = 0; i < n; i++) {
        double m[16];
        for (double& v : m) std::scanf("%lf", &v);
        poses.push_back(pose_of(m));
      }
      long found = 0;
      double t0 = cpu_ns();
      for (int r = 0; r < reps; r++)
        for (int i = 0; i < n; i++) {
          auto sols = opw_kinematics::inverse(p, poses[static_cast<size_t>(i)]);
          // Read every solution as a caller would (and keep the call from being elided).
          for (const auto& s : sols) found += opw_kinematics::isValid(s) ? 1 : 0;
        }
      double t1 = cpu_ns();
      std::printf("%.3f %ld\n", (t1 - t0) / (static_cast<double>(reps) * n), found);
    } else {
      return 2;
    }
    std::fflush(stdout);
  }
  return 0;
}
