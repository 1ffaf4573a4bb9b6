// report_render_check: renders an HTML report in headless Chromium and checks what a reader
// would see -- the rendered DOM holds the expected markup and text and at least N SVG plots
// with data marks (svg_plot.hpp: class="plot", class="mark"), every piece of text in every SVG
// lies inside its SVG and overlaps no other text of it, and the screenshot is a real picture (a
// PNG of the size asked for, not blank: many distinct colours, ink on the page).
//
//   report_render_check REPORT.html --min-plots N [--expect TEXT]... [--reject TEXT]... [--keep DIR]
//
// The layout check: a copy of the page with a small script added at the end of its body, which
// takes the rendered box (getBoundingClientRect: the glyph cells of the font Chromium chose,
// after any transform) of every non-empty <text> of every <svg>, compares it with the SVG's
// content box (inside its border) and with the box of every other text of that SVG, and writes
// its findings into the page (<pre id="kincal-layout">), read back with --dump-dom. A text more
// than 1 px outside, or two texts overlapping by more than 1 px both ways, fails the check; the
// first 40 findings are printed, each naming the plot (its aria-label), the text and the boxes.
//
// --reject TEXT: the DOM must not contain it (e.g. class="n off", a value marked as wrong).
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

// The script the layout check adds to its copy of the page (see the top of the file).
constexpr const char* kLayoutScript = R"(<script>(function () {
  const tolerance = 1;
  const found = [];
  let texts = 0, svgs = 0;
  const box = (r) => '[' + r.left.toFixed(1) + ', ' + r.right.toFixed(1) + '] x [' + r.top.toFixed(1) + ', ' +
      r.bottom.toFixed(1) + '] px';
  document.querySelectorAll('svg').forEach((svg, index) => {
    ++svgs;
    const outer = svg.getBoundingClientRect();
    const inner = {left: outer.left + svg.clientLeft, top: outer.top + svg.clientTop};
    inner.right = inner.left + svg.clientWidth;
    inner.bottom = inner.top + svg.clientHeight;
    const name = svg.getAttribute('aria-label') || 'svg ' + (index + 1);
    const items = [];
    svg.querySelectorAll('text').forEach((t) => {
      const r = t.getBoundingClientRect();
      if (t.textContent.trim() !== '' && r.width > 0 && r.height > 0) items.push({text: t.textContent, r: r});
    });
    texts += items.length;
    for (const a of items)
      if (a.r.left < inner.left - tolerance || a.r.top < inner.top - tolerance ||
          a.r.right > inner.right + tolerance || a.r.bottom > inner.bottom + tolerance)
        found.push('outside\t' + name + '\t' + a.text + '\ttext ' + box(a.r) + ', plot ' + box(inner));
    for (let i = 0; i < items.length; ++i)
      for (let j = i + 1; j < items.length; ++j) {
        const a = items[i].r, b = items[j].r;
        if (Math.min(a.right, b.right) - Math.max(a.left, b.left) > tolerance &&
            Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top) > tolerance)
          found.push('overlap\t' + name + '\t' + items[i].text + '\t' + items[j].text + '\t' + box(a) + ' and ' +
                     box(b));
      }
  });
  const pre = document.createElement('pre');
  pre.id = 'kincal-layout';
  pre.textContent = 'measured\t' + texts + '\t' + svgs + '\n' + found.join('\n');
  document.body.appendChild(pre);
})();</script>)";

// The page with kLayoutScript added at the end of its body.
std::string with_layout_script(const std::string& html) {
  const std::size_t body_end = html.rfind("</body>");
  std::string out = html;
  out.insert(body_end == std::string::npos ? out.size() : body_end, kLayoutScript);
  return out;
}

// The text of the layout check's <pre> in a dumped DOM, entities decoded; "" when absent.
std::string layout_findings(const std::string& dom) {
  const std::string open = "<pre id=\"kincal-layout\">";
  const std::size_t begin = dom.find(open);
  if (begin == std::string::npos) return "";
  const std::size_t end = dom.find("</pre>", begin);
  std::string text =
      dom.substr(begin + open.size(), end == std::string::npos ? std::string::npos : end - begin - open.size());
  const std::pair<const char*, const char*> entities[] = {{"&lt;", "<"},  {"&gt;", ">"},   {"&quot;", "\""},
                                                          {"&#39;", "'"}, {"&nbsp;", " "}, {"&amp;", "&"}};
  for (const auto& [entity, character] : entities)
    for (std::size_t at = text.find(entity); at != std::string::npos; at = text.find(entity, at + 1))
      text.replace(at, std::string(entity).size(), character);
  return text;
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t at = text.find(separator); at != std::string::npos; at = text.find(separator, start)) {
    parts.push_back(text.substr(start, at - start));
    start = at + 1;
  }
  parts.push_back(text.substr(start));
  return parts;
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
  std::vector<std::string> expected, rejected;
  app.add_option("report", html_path, "the HTML report")->required()->check(CLI::ExistingFile);
  app.add_option("--min-plots", min_plots, "at least this many <svg class=\"plot\"> with data marks");
  app.add_option("--expect", expected, "text or markup the rendered DOM must contain (repeatable)");
  app.add_option("--reject", rejected, "text or markup the rendered DOM must not contain (repeatable)");
  app.add_option("--width", width, "window width, px");
  app.add_option("--height", height, "window height, px");
  app.add_option("--keep", keep, "copy the screenshot, the DOM and the layout findings into this directory");
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
  const fs::path shot = work / "screenshot.png", dom_path = work / "dom.html", layout_page = work / "layout.html",
                 layout_path = work / "layout_dom.html";
  const std::string url = "file://" + fs::absolute(html_path).string();
  {
    std::ofstream copy(layout_page, std::ios::binary);
    copy << with_layout_script(read_text(html_path));
    if (!copy) {
      std::cerr << "report_render_check: cannot write " << layout_page << "\n";
      fs::remove_all(work);
      return 2;
    }
  }
  const std::vector<std::string> common = {"--headless",
                                           "--no-sandbox",
                                           "--disable-gpu",
                                           "--hide-scrollbars",
                                           "--no-first-run",
                                           "--no-default-browser-check",
                                           "--user-data-dir=" + (work / "profile").string(),
                                           "--window-size=" + std::to_string(width) + "," + std::to_string(height)};
  std::vector<std::string> shot_args = common, dom_args = common, layout_args = common;
  shot_args.insert(shot_args.end(), {"--screenshot=" + shot.string(), url});
  dom_args.insert(dom_args.end(), {"--dump-dom", url});
  layout_args.insert(layout_args.end(), {"--dump-dom", "file://" + layout_page.string()});
  const int shot_status = run_chromium(chromium, shot_args, work, work / "screenshot.out");
  const int dom_status = run_chromium(chromium, dom_args, work, dom_path);
  const int layout_status = run_chromium(chromium, layout_args, work, layout_path);
  if (shot_status != 0 || dom_status != 0 || layout_status != 0) {
    std::cerr << "report_render_check: chromium (" << chromium << ") failed: exit " << shot_status << " (screenshot), "
              << dom_status << " (dump-dom), " << layout_status << " (layout); its messages:\n"
              << read_text(work / "screenshot.out.log") << read_text(work / "dom.html.log")
              << read_text(work / "layout_dom.html.log");
    fs::remove_all(work);
    return 2;
  }
  const std::string dom = read_text(dom_path);
  const std::string layout = layout_findings(read_text(layout_path));
  const cv::Mat image = cv::imread(shot.string(), cv::IMREAD_COLOR);
  if (!keep.empty()) {
    fs::create_directories(keep);
    fs::copy_file(shot, fs::path(keep) / "screenshot.png", fs::copy_options::overwrite_existing);
    fs::copy_file(dom_path, fs::path(keep) / "dom.html", fs::copy_options::overwrite_existing);
    std::ofstream(fs::path(keep) / "layout.txt", std::ios::binary) << layout << "\n";
  }
  fs::remove_all(work);

  int failures = 0;
  const auto check = [&failures](bool ok, const std::string& what) {
    std::cout << (ok ? "ok    " : "FAIL  ") << what << "\n";
    failures += ok ? 0 : 1;
  };
  check(dom.find("<body") != std::string::npos, "the DOM has a body (" + std::to_string(dom.size()) + " bytes)");
  for (const std::string& text : expected) check(dom.find(text) != std::string::npos, "the DOM contains " + text);
  for (const std::string& text : rejected)
    check(dom.find(text) == std::string::npos, "the DOM does not contain " + text);

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

  // The layout: "measured\tTEXTS\tSVGS", then one finding per line.
  const std::vector<std::string> findings = split(layout, '\n');
  const std::vector<std::string> totals = split(findings.front(), '\t');
  check(
      totals.size() == 3 && totals[0] == "measured",
      "the layout script ran in the page" + (totals.size() == 3 ? " (" + totals[1] + " texts in " + totals[2] + " SVGs)"
                                                                : std::string(" (no result in the DOM)")));
  int outside = 0, overlapping = 0;
  for (std::size_t i = 1; i < findings.size(); ++i) {
    const std::vector<std::string> f = split(findings[i], '\t');
    if (f.size() < 4) continue;
    const bool is_outside = f[0] == "outside";
    (is_outside ? outside : overlapping) += 1;
    if (outside + overlapping <= 40)
      std::cout << "FAIL  " << (is_outside ? "text outside its plot" : "texts overlap") << " in \"" << f[1] << "\": \""
                << f[2] << "\"" << (is_outside ? "" : " and \"" + f[3] + "\"") << ": " << f.back() << "\n";
  }
  check(outside == 0, std::to_string(outside) + " texts outside their plot (1 px tolerance)");
  check(overlapping == 0, std::to_string(overlapping) + " pairs of texts overlapping in a plot (1 px tolerance)");

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
