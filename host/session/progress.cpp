#include "host/session/progress.hpp"

#include <cstdio>
#include <ostream>

namespace kincal::session {

Progress::Progress(std::ostream& out, bool terminal, std::string what, int total, int already_done)
    : out_(out),
      terminal_(terminal),
      what_(std::move(what)),
      total_(total),
      done_(already_done),
      done_at_start_(already_done) {
  if (already_done > 0) out_ << what_ << ": resuming with " << already_done << " of " << total << " done\n";
}

std::string Progress::format_duration(double seconds) {
  const long s = seconds < 0 ? 0 : static_cast<long>(seconds + 0.5);
  char text[32];
  if (s >= 3600)
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  return text;
}

void Progress::step(const std::string& note) {
  ++done_;
  draw(note);
}

void Progress::draw(const std::string& note) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const int done_here = done_ - done_at_start_;
  const std::string eta = done_here > 0 ? format_duration(elapsed / done_here * (total_ - done_)) : std::string("?");
  constexpr int kWidth = 30;
  const int filled = total_ > 0 ? kWidth * done_ / total_ : kWidth;
  const std::string bar =
      std::string(static_cast<std::size_t>(filled), '#') + std::string(static_cast<std::size_t>(kWidth - filled), '.');
  const std::string line = what_ + " [" + bar + "] " + std::to_string(done_) + "/" + std::to_string(total_) + "  " +
                           format_duration(elapsed) + " elapsed  ETA " + eta + (note.empty() ? "" : "  " + note);
  if (terminal_) {
    out_ << '\r' << line << "\x1b[K" << std::flush;
  } else {
    const int decile = total_ > 0 ? 10 * done_ / total_ : 10;
    if (decile != last_decile_) out_ << line << '\n';
    last_decile_ = decile;
  }
}

void Progress::finish() {
  if (terminal_) out_ << '\n';
  out_ << std::flush;
}

}  // namespace kincal::session
