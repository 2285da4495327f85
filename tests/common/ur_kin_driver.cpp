// A command-line driver around ROS-Industrial's ur_kinematics (ur_kin.cpp), written
// for fitup's tests and benchmarks. ur_kin.cpp itself is never committed: it is
// compiled from the folder FITUP_UR_KIN_SRC names (the universal_robot checkout), one
// binary per arm (-DUR5e_PARAMS, ...), by tests/common/ur_kin.rs.
//
// stdin, one request per line, lengths in metres, poses row-major 4x4 of the
// end effector in ur_kin's base frame:
//   fk q1 .. q6            -> 16 numbers
//   ik T00 .. T33          -> n, then n joint vectors (6 numbers each), one line
//   bench reps n T[16*n]   -> CPU ns per inverse() call over reps passes of the n
//                             targets, and the total number of solutions found
#include <ur_kinematics/ur_kin.h>

#include <cstdio>
#include <cstring>
#include <ctime>
#include <vector>

static double cpu_ns() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e9 + t.tv_nsec;
}

int main() {
  char mode[16];
  while (std::scanf("%15s", mode) == 1) {
    if (std::strcmp(mode, "fk") == 0) {
      double q[6], T[16];
      for (double& v : q) std::scanf("%lf", &v);
      ur_kinematics::forward(q, T);
      for (double v : T) std::printf("%.17g ", v);
      std::printf("\n");
    } else if (std::strcmp(mode, "ik") == 0) {
      double T[16], sols[48];
      for (double& v : T) std::scanf("%lf", &v);
      int n = ur_kinematics::inverse(T, sols, 0.0);
      std::printf("%d", n);
      for (int i = 0; i < 6 * n; i++) std::printf(" %.17g", sols[i]);
      std::printf("\n");
    } else if (std::strcmp(mode, "bench") == 0) {
      int reps = 0, n = 0;
      std::scanf("%d %d", &reps, &n);
      std::vector<double> T(16 * static_cast<size_t>(n));
      for (double& v : T) std::scanf("%lf", &v);
      double sols[48];
      long found = 0;
      double t0 = cpu_ns();
      for (int r = 0; r < reps; r++)
        for (int i = 0; i < n; i++) found += ur_kinematics::inverse(&T[16 * i], sols, 0.0);
      double t1 = cpu_ns();
      std::printf("%.3f %ld\n", (t1 - t0) / (static_cast<double>(reps) * n), found);
    } else {
      return 2;
    }
    std::fflush(stdout);
  }
  return 0;
}
