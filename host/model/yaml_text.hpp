// YAML documents kincal reads from text (the model file, plan constraints): yaml-cpp's errors as
// model::InputError naming where -- SOURCE:LINE:COLUMN for a syntax error, SOURCE:LINE for a
// conversion that fails inside yaml-cpp while `read` walks the document. What `read` throws
// itself passes through unchanged. Before the tree is built the text passes
// files::check_yaml_text (files/yaml_limits.hpp): at most kMaxYamlNodes nodes, no key given twice
// in one mapping, one document.
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "host/files/yaml_limits.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::model {

template <class Read>
auto read_yaml_text(const std::string& text, const std::string& source, Read&& read) {
  YAML::Node root;
  try {
    files::check_yaml_text<InputError>(text, source);
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(source + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                     ": YAML syntax: " + e.msg);
  }
  try {
    return read(root);
  } catch (const YAML::Exception& e) {  // a conversion deep inside yaml-cpp
    throw InputError(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace kincal::model
