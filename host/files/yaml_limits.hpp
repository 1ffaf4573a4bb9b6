// What every YAML text kincal reads with yaml-cpp must pass before YAML::Load builds its tree
// (the model file, plan constraints, the platform's geometry, a ROS camera file): one pass over
// the parser's events, in memory bounded by the text, refusing
//   - more than kMaxYamlNodes nodes (scalars, nulls, aliases, lists, mappings): yaml-cpp's tree
//     takes about 240 bytes of memory per byte of a dense list ("[0,0,0,...]"), so a 16 MiB
//     settings file would take 3.5 GB and half a minute; no file kincal reads has a thousand;
//   - a scalar key given twice in one mapping: yaml-cpp keeps both and looks up the first, so the
//     second value would be silently ignored (keys compared as text; complex and alias keys are
//     not compared);
//   - a second document: YAML::Load reads the first and ignores the rest;
//   - lists and mappings nested deeper than yaml-cpp's guard (500 levels), which yaml-cpp calls a
//     "bad file": named as too deep.
// An alias is one event however much it stands for (no expansion). The message names the source,
// LINE:COLUMN and what: "c.yaml:5:3: 'floor' given twice in this mapping (first at 1:1)". A
// syntax error is left to the caller: YAML::ParserException passes through (with its mark), as
// YAML::Load would throw it.
#pragma once

#include <cstddef>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include "host/files/input_file.hpp"

namespace kincal::files {

inline constexpr std::size_t kMaxYamlNodes = 100000;

namespace yaml_limits_detail {

inline std::string where(const std::string& source, const YAML::Mark& mark) {
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

// The first document's events: counts nodes and compares each mapping's scalar keys.
template <class Error>
class FirstDocument : public YAML::EventHandler {
 public:
  explicit FirstDocument(const std::string& source) : source_(source) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { node(nullptr, mark); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { node(nullptr, mark); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    node(&value, mark);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    node(nullptr, mark);
    frames_.push_back({false, true, {}});
  }
  void OnSequenceEnd() override { frames_.pop_back(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    node(nullptr, mark);
    frames_.push_back({true, true, {}});
  }
  void OnMapEnd() override { frames_.pop_back(); }

 private:
  struct Frame {
    bool map = false;
    bool key_next = true;                    // a mapping's next node is a key
    std::map<std::string, YAML::Mark> keys;  // its scalar keys so far, where
  };

  // A node starts in the innermost collection; scalar is its text when it is a scalar.
  void node(const std::string* scalar, const YAML::Mark& mark) {
    if (++nodes_ > kMaxYamlNodes)
      throw Error(where(source_, mark) + ": more than " + std::to_string(kMaxYamlNodes) +
                  " YAML nodes (values, lists, mappings): too many for any file kincal reads");
    if (frames_.empty() || !frames_.back().map) return;
    Frame& f = frames_.back();
    if (f.key_next && scalar) {
      const auto [first, inserted] = f.keys.emplace(*scalar, mark);
      if (!inserted)
        throw Error(where(source_, mark) + ": '" + excerpt(*scalar) + "' given twice in this mapping (first at " +
                    std::to_string(first->second.line + 1) + ":" + std::to_string(first->second.column + 1) + ")");
    }
    f.key_next = !f.key_next;
  }

  const std::string& source_;
  std::size_t nodes_ = 0;
  std::vector<Frame> frames_;
};

// Any document after the first.
template <class Error>
class NoSecondDocument : public YAML::EventHandler {
 public:
  explicit NoSecondDocument(const std::string& source) : source_(source) {}

  void OnDocumentStart(const YAML::Mark& mark) override {
    throw Error(where(source_, mark) + ": a second YAML document (kincal reads one; '---' starts another)");
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  const std::string& source_;
};

}  // namespace yaml_limits_detail

// Throws Error (constructible from a message) as the top of this file says; `source` names the
// text in messages.
template <class Error>
void check_yaml_text(const std::string& text, const std::string& source) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  yaml_limits_detail::FirstDocument<Error> first(source);
  try {
    parser.HandleNextDocument(first);
  } catch (const YAML::DeepRecursion& e) {
    throw Error(yaml_limits_detail::where(source, e.mark) + ": lists and mappings nested more than " +
                std::to_string(e.depth() - 1) + " deep");
  }
  yaml_limits_detail::NoSecondDocument<Error> rest(source);
  parser.HandleNextDocument(rest);
}

}  // namespace kincal::files
