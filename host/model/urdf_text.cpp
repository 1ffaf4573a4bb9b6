#include "host/model/urdf_text.hpp"

#include <algorithm>
#include <cctype>

namespace kincal::model {

namespace {

// tinyxml2's XMLUtil::IsWhiteSpace, IsNameStartChar and IsNameChar.
bool is_space(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }
bool is_name_start(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u >= 128 || std::isalpha(u) != 0 || c == ':' || c == '_';
}
bool is_name_char(char c) {
  return is_name_start(c) || std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '-';
}

class Scanner {
 public:
  explicit Scanner(std::string_view text) : text_(text) {}

  XmlTextMap run() {
    XmlTextMap map;
    map.end = text_.size();
    skip_space();
    if (text_.substr(p_).starts_with("\xEF\xBB\xBF")) {
      p_ += 3;
      map.prolog_end = p_;
    }
    skip_space();
    // tinyxml2 takes every "<?...?>" for a declaration and refuses one after anything else.
    for (; text_.substr(p_).starts_with("<?"); skip_space()) {
      p_ = after("?>", p_ + 2);
      map.prolog_end = p_;
      map.has_declaration = true;
    }
    for (p_ = text_.find('<', p_); p_ < text_.size(); p_ = text_.find('<', p_)) {
      const std::string_view rest = text_.substr(p_);
      if (rest.starts_with("<?")) {
        p_ = after("?>", p_ + 2);
      } else if (rest.starts_with("<!--")) {
        p_ = after("-->", p_ + 4);
      } else if (rest.starts_with("<![CDATA[")) {
        p_ = after("]]>", p_ + 9);
      } else if (rest.starts_with("<!")) {
        p_ = after(">", p_ + 2);
      } else if (const std::size_t at = p_; !tag(map)) {
        map.end = at;
        map.end_line = line_at(at);
        break;
      }
    }
    return map;
  }

 private:
  std::size_t after(std::string_view end, std::size_t from) const {
    const std::size_t at = text_.find(end, std::min(from, text_.size()));
    return at == std::string_view::npos ? text_.size() : at + end.size();
  }
  void skip_space() {
    while (p_ < text_.size() && is_space(text_[p_])) ++p_;
  }
  std::string_view name() {
    const std::size_t begin = p_;
    if (p_ < text_.size() && is_name_start(text_[p_]))
      while (p_ < text_.size() && is_name_char(text_[p_])) ++p_;
    return text_.substr(begin, p_ - begin);
  }
  int line_at(std::size_t offset) {
    line_ += static_cast<int>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(counted_),
                                         text_.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
    counted_ = offset;
    return line_;
  }

  // A start or end tag at p_ ('<'); a start tag goes into the map. False at an end tag that
  // closes nothing: tinyxml2 ends the document there (what follows is not parsed).
  bool tag(XmlTextMap& map) {
    XmlElementSpan e;
    e.line = line_at(p_);
    ++p_;
    skip_space();
    const bool closing = p_ < text_.size() && text_[p_] == '/';
    if (closing) ++p_;
    e.name = name();
    e.name_end = p_;
    while (p_ < text_.size()) {
      skip_space();
      if (p_ >= text_.size() || !is_name_start(text_[p_])) break;
      XmlAttributeSpan a;
      a.name = name();
      skip_space();
      if (p_ < text_.size() && text_[p_] == '=') ++p_;
      skip_space();
      if (p_ >= text_.size()) break;
      const char quote = text_[p_];
      if (e.attributes.empty()) e.quote = quote;
      a.value_begin = p_ + 1;
      a.value_end = std::min(text_.find(quote, a.value_begin), text_.size());
      p_ = std::min(a.value_end + 1, text_.size());
      e.attributes.push_back(a);
    }
    const bool empty = p_ < text_.size() && text_[p_] == '/';
    p_ = after(">", p_);  // at '>' or "/>"
    e.start_tag_end = p_;
    if (closing && !empty) return depth_-- > 0;
    if (closing && map.sealed_end_tag_line == 0) map.sealed_end_tag_line = e.line;  // "</a/>": an element a
    if (!empty) ++depth_;
    map.elements.push_back(std::move(e));
    return true;
  }

  std::string_view text_;
  std::size_t p_ = 0;
  std::size_t counted_ = 0;  // line_ is the line of byte counted_
  int line_ = 1;
  int depth_ = 0;  // elements open at p_
};

}  // namespace

const XmlAttributeSpan* XmlElementSpan::attribute(std::string_view attribute_name) const {
  const auto it = std::find_if(attributes.begin(), attributes.end(),
                               [&](const XmlAttributeSpan& a) { return a.name == attribute_name; });
  return it == attributes.end() ? nullptr : &*it;
}

XmlTextMap map_xml_text(std::string_view text) { return Scanner(text).run(); }

}  // namespace kincal::model
