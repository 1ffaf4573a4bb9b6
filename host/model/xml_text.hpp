// Text inside XML and HTML markup: the one escaping that the URDF writer (urdf.hpp) and the HTML
// report (host/report) put every piece of free text through (names, titles, notes).
//
// Header-only, so that host/report, which knows nothing of robot models, uses it without linking
// the model library. XML comments are not escaped text: a "--" inside one is not dealt with here.
#pragma once

#include <string>
#include <string_view>

namespace kincal::model {

// & < > " ' as entities (' as &#39;, which XML 1.0 and every HTML read): safe in element
// content and in attribute values quoted with either quote.
inline std::string escape_xml_text(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace kincal::model
