// A progress bar with an ETA for long sessions (issue #6), on the terminal the operator watches.
//
// On a terminal: one line redrawn in place ("[#####.....] 12/40 poses  0:42 elapsed  ETA 1:38").
// Elsewhere (a log file, CI): a plain line at every tenth of the run, so logs stay readable.
// The ETA is the mean time per completed step times the steps left, counting only steps done in
// this run (a resumed session does not count the restored ones as instantaneous).
// Thread safety: one thread. Cost: one write per update.
#pragma once

#include <chrono>
#include <iosfwd>
#include <string>

namespace kincal::session {

class Progress {
 public:
  // `total` steps, of which `already_done` were done before this run (resume).
  Progress(std::ostream& out, bool terminal, std::string what, int total, int already_done);
  void step(const std::string& note = {});  // one more done
  void finish();

  // "m:ss" or "h:mm:ss"; exported for tests.
  static std::string format_duration(double seconds);

 private:
  void draw(const std::string& note);

  std::ostream& out_;
  bool terminal_;
  std::string what_;
  int total_, done_, done_at_start_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace kincal::session
