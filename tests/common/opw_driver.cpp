// A command-line driver around opw_kinematics (Jmeyer1292/opw_kinematics, the C++
// closed form of ortho-parallel arms with a spherical wrist), written for fitup's
// kinematics benchmark. The library (header-only, Eigen) is never committed: it is
// compiled from the checkout FITUP_OPW_KIN_SRC names by tests/bench/kinematics.rs.
//
// argv: a1 a2 b c1 c2 c3 c4 (any length unit). stdin, one request per line:
//   fk q1 .. q6            -> 16 numbers (row-major 4x4)
//   bench reps n T[16*n]   -> CPU ns per inverse() call over reps passes of the n
//                             targets, and the number of valid (finite) solutions
#include <opw_kinematics/opw_kinematics.h>

#include <cmath>
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

int main(int argc, char** argv) {
  if (argc != 8) return 2;
  opw_kinematics::Parameters<double> p;
  double* v[7] = {&p.a1, &p.a2, &p.b, &p.c1, &p.c2, &p.c3, &p.c4};
  for (int i = 0; i < 7; i++) *v[i] = std::atof(argv[i + 1]);
  char mode[16];
  while (std::scanf("%15s", mode) == 1) {
    if (std::strcmp(mode, "fk") == 0) {
      std::array<double, 6> q;
      for (double& x : q) std::scanf("%lf", &x);
      Eigen::Matrix4d m = opw_kinematics::forward(p, q).matrix();
      for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) std::printf("%.17g ", m(i, j));
      std::printf("\n");
    } else if (std::strcmp(mode, "bench") == 0) {
      int reps = 0, n = 0;
      std::scanf("%d %d", &reps, &n);
      std::vector<opw_kinematics::Transform<double>> targets(n);
      for (auto& t : targets) {
        Eigen::Matrix4d m;
        for (int i = 0; i < 4; i++)
          for (int j = 0; j < 4; j++) std::scanf("%lf", &m(i, j));
        t.matrix() = m;
      }
      long found = 0;
      double t0 = cpu_ns();
      for (int r = 0; r < reps; r++)
        for (const auto& t : targets) {
          auto sols = opw_kinematics::inverse(p, t);
          found += std::isfinite(sols[0][0]);
        }
      double t1 = cpu_ns();
      long valid = 0;
      for (const auto& t : targets) {
        auto sols = opw_kinematics::inverse(p, t);
        for (const auto& s : sols) valid += std::isfinite(s[0]);
      }
      std::printf("%.3f %ld %ld\n", (t1 - t0) / (static_cast<double>(reps) * n), valid, found);
    } else {
      return 2;
    }
    std::fflush(stdout);
  }
  return 0;
}
