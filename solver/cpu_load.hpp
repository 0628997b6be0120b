// How many cores other processes keep busy, from /proc/stat and this process's own CPU time: the
// time loop runs fewer threads than asked while the machine is loaded (issue 27, item 9). With one
// of two cores taken by another job, two threads that meet at a barrier several times a step waited
// a scheduler slice each time: 280.8 s against 6.8 s on one thread. Results do not depend on the
// thread count (every scatter's summation order is fixed), so the count may change between steps.
#pragma once

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace swmpm {

class CpuLoad {
 public:
  CpuLoad() { sample(last_); }

  /// Cores other processes kept busy since the previous call (or construction), averaged over the
  /// interval; a negative value when the interval is too short to tell (< 0.1 s) or /proc/stat is
  /// unreadable.
  double others_busy_cores() {
    Sample now;
    if (!sample(now) || !last_.ok) return -1.0;
    const double wall = now.total - last_.total;  // jiffies summed over every core
    if (wall < 0.1 * hz_ * now.cores) return -1.0;
    const double busy = (now.busy - last_.busy) - (now.own - last_.own);  // jiffies, other processes'
    last_ = now;
    return std::max(0.0, busy / (wall / now.cores));
  }

  int cores() const { return last_.cores; }

 private:
  struct Sample {
    bool ok = false;
    int cores = 1;
    double total = 0.0, busy = 0.0, own = 0.0;  // jiffies
  };

  bool sample(Sample& s) const {
    std::ifstream in("/proc/stat");
    std::string line;
    if (!std::getline(in, line) || line.compare(0, 4, "cpu ") != 0) return false;
    std::istringstream is(line.substr(4));
    // user nice system idle iowait irq softirq steal (guest time is inside user)
    double f[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (double& v : f) is >> v;
    s.total = f[0] + f[1] + f[2] + f[3] + f[4] + f[5] + f[6] + f[7];
    s.busy = s.total - f[3] - f[4];
    s.cores = 0;
    while (std::getline(in, line) && line.compare(0, 3, "cpu") == 0) ++s.cores;
    s.cores = std::max(s.cores, 1);
    rusage r{};
    getrusage(RUSAGE_SELF, &r);
    const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
    s.own = (seconds(r.ru_utime) + seconds(r.ru_stime)) * hz_;
    s.ok = true;
    return true;
  }

  double hz_ = static_cast<double>(sysconf(_SC_CLK_TCK));
  Sample last_;
};

}  // namespace swmpm
