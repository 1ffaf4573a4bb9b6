// report_render_check: renders an HTML report in headless Chromium and checks what a reader
// would see -- the rendered DOM holds the expected markup and text and at least N SVG plots
// with data marks (svg_plot.hpp: class="plot", class="mark"), and the screenshot is a real
// picture (a PNG of the size asked for, not blank: many distinct colours, ink on the page).
//
//   report_render_check REPORT.html --min-plots N [--expect TEXT]... [--keep DIR]
//
// TEXT is matched against the DOM as Chromium serializes it (so '&' in text is "&amp;").
// Chromium: $KINCAL_CHROMIUM, else `chromium` on PATH (Debian package chromium, installed by
// toolchain/setup-debian.sh); without it the check fails saying so. Chromium runs with HOME and
// its profile in a fresh temporary directory. Exit status: 0 all checks pass, 1 a check
// failed, 2 Chromium or the files could not be used.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

extern char** environ;

namespace {

namespace fs = std::filesystem;

std::string find_chromium() {
  if (const char* given = std::getenv("KINCAL_CHROMIUM")) return ::access(given, X_OK) == 0 ? given : "";
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t colon = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, colon - start)) / "chromium";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = colon + 1;
  }
  return "";
}

// Runs chromium with `args`, HOME set to `home`, stdout to `stdout_path`; its exit status.
// Its stderr (much noise about D-Bus) goes to `stdout_path`.log.
int run_chromium(const std::string& chromium, const std::vector<std::string>& args, const fs::path& home,
                 const fs::path& stdout_path) {
  std::vector<std::string> env_text = {"HOME=" + home.string()};
  for (char** e = environ; *e; ++e)
    if (std::string(*e).rfind("HOME=", 0) != 0) env_text.emplace_back(*e);
  std::vector<char*> env, argv;
  for (std::string& e : env_text) env.push_back(e.data());
  env.push_back(nullptr);
  std::vector<std::string> arg_text = {chromium};
  arg_text.insert(arg_text.end(), args.begin(), args.end());
  for (std::string& a : arg_text) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log = stdout_path.string() + ".log";
  posix_spawn_file_actions_addopen(&actions, 1, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, chromium.c_str(), &actions, nullptr, argv.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

int count(const std::string& text, const std::string& what, std::size_t from = 0, std::size_t to = std::string::npos) {
  int n = 0;
  for (std::size_t at = text.find(what, from); at != std::string::npos && at < to; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Renders an HTML report in headless Chromium and checks the DOM and the screenshot");
  std::string html_path, keep;
  int min_plots = 1, width = 1280, height = 2000;
  std::vector<std::string> expected;
  app.add_option("report", html_path, "the HTML report")->required()->check(CLI::ExistingFile);
  app.add_option("--min-plots", min_plots, "at least this many <svg class=\"plot\"> with data marks");
  app.add_option("--expect", expected, "text or markup the rendered DOM must contain (repeatable)");
  app.add_option("--width", width, "window width, px");
  app.add_option("--height", height, "window height, px");
  app.add_option("--keep", keep, "copy the screenshot and the DOM into this directory");
  CLI11_PARSE(app, argc, argv);

  const std::string chromium = find_chromium();
  if (chromium.empty()) {
    std::cerr << "report_render_check: FAIL: chromium not found ($KINCAL_CHROMIUM or PATH; the Debian package "
                 "chromium, which toolchain/setup-debian.sh installs)\n";
    return 2;
  }
  char pattern[] = "/tmp/kincal_render_XXXXXX";
  if (!::mkdtemp(pattern)) {
    std::cerr << "report_render_check: cannot make a temporary directory\n";
    return 2;
  }
  const fs::path work = pattern;
  const fs::path shot = work / "screenshot.png", dom_path = work / "dom.html";
  const std::string url = "file://" + fs::absolute(html_path).string();
  const std::vector<std::string> common = {"--headless",
                                           "--no-sandbox",
                                           "--disable-gpu",
                                           "--hide-scrollbars",
                                           "--no-first-run",
                                           "--no-default-browser-check",
                                           "--user-data-dir=" + (work / "profile").string(),
                                           "--window-size=" + std::to_string(width) + "," + std::to_string(height)};
  std::vector<std::string> shot_args = common, dom_args = common;
  shot_args.insert(shot_args.end(), {"--screenshot=" + shot.string(), url});
  dom_args.insert(dom_args.end(), {"--dump-dom", url});
  const int shot_status = run_chromium(chromium, shot_args, work, work / "screenshot.out");
  const int dom_status = run_chromium(chromium, dom_args, work, dom_path);
  if (shot_status != 0 || dom_status != 0) {
    std::cerr << "report_render_check: chromium (" << chromium << ") failed: exit " << shot_status << " (screenshot), "
              << dom_status << " (dump-dom); its messages:\n"
              << read_text(work / "screenshot.out.log") << read_text(work / "dom.html.log");
    fs::remove_all(work);
    return 2;
  }
  const std::string dom = read_text(dom_path);
  const cv::Mat image = cv::imread(shot.string(), cv::IMREAD_COLOR);
  if (!keep.empty()) {
    fs::create_directories(keep);
    fs::copy_file(shot, fs::path(keep) / "screenshot.png", fs::copy_options::overwrite_existing);
    fs::copy_file(dom_path, fs::path(keep) / "dom.html", fs::copy_options::overwrite_existing);
  }
  fs::remove_all(work);

  int failures = 0;
  const auto check = [&failures](bool ok, const std::string& what) {
    std::cout << (ok ? "ok    " : "FAIL  ") << what << "\n";
    failures += ok ? 0 : 1;
  };
  check(dom.find("<body") != std::string::npos, "the DOM has a body (" + std::to_string(dom.size()) + " bytes)");
  for (const std::string& text : expected) check(dom.find(text) != std::string::npos, "the DOM contains " + text);

  int plots = 0, plots_with_data = 0, marks = 0;
  const std::string plot_tag = "<svg class=\"plot\"";
  for (std::size_t at = dom.find(plot_tag); at != std::string::npos; at = dom.find(plot_tag, at + 1)) {
    const std::size_t end = dom.find("</svg>", at);
    const int n = count(dom, "class=\"mark\"", at, end);
    ++plots;
    plots_with_data += n > 0 ? 1 : 0;
    marks += n;
  }
  check(plots_with_data >= min_plots, std::to_string(plots_with_data) + " of " + std::to_string(plots) +
                                          " plots have data (" + std::to_string(marks) + " marks), at least " +
                                          std::to_string(min_plots) + " wanted");

  check(!image.empty(), "the screenshot is a PNG OpenCV reads");
  if (!image.empty()) {
    check(image.cols == width && image.rows == height,
          "the screenshot is " + std::to_string(image.cols) + " x " + std::to_string(image.rows) + " px, " +
              std::to_string(width) + " x " + std::to_string(height) + " asked");
    std::set<int> colours;
    long inked = 0;
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x) {
        const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
        colours.insert((p[0] << 16) | (p[1] << 8) | p[2]);
        inked += (p[0] < 200 || p[1] < 200 || p[2] < 200) ? 1 : 0;
      }
    const double ink = static_cast<double>(inked) / (static_cast<double>(image.total()));
    check(colours.size() >= 16, std::to_string(colours.size()) + " distinct colours in the screenshot (16 wanted)");
    check(ink >= 0.01, "ink on " + std::to_string(ink * 100.0) + " % of the screenshot (1 % wanted)");
  }
  std::cout << (failures == 0 ? "PASS" : "FAIL") << ": " << html_path << "\n";
  return failures == 0 ? 0 : 1;
}
