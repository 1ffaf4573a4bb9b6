// Where the elements of a URDF sit in its text, so that `kincal urdf --original` edits attribute
// values in place and keeps every other byte (write_calibrated_urdf, urdf.hpp).
//
// map_xml_text() scans the text with the rules tinyxml2 parses it by (tinyxml2 9, XMLDocument::
// Identify and XMLElement::ParseAttributes): "<?" up to "?>", "<!--" up to "-->", "<![CDATA[" up
// to "]]>", any other "<!" up to ">", end tags "</" up to ">" ("</a/>" is an empty element a,
// as tinyxml2 reads it), and start tags with their
// attributes (name, white space, '=', white space, a value in '"' or '\'' up to the same quote;
// white space between attributes optional); the document ends at an end tag that closes nothing,
// as tinyxml2's does (it ignores the rest). So the elements come out in document order, the
// order in which a pre-order walk of tinyxml2's tree meets them, and element k of the map is
// the k-th element of that walk. The reader records that index for each joint and its <origin>
// (UrdfJoint::element, origin_element); the writer checks the name and line of every element it
// edits against the map before it touches the text.
//
// Precondition: tinyxml2 parsed `text` without error and it holds no NUL byte (the URDF reader
// refuses those): the scan relies on the text being well-formed and does no checking of its own
// beyond not reading past the end. Cost: one pass over the text; memory: one entry per element
// and attribute. The spans are offsets into `text`; names are views into it.
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

namespace kincal::model {

struct XmlAttributeSpan {
  std::string_view name;
  std::size_t value_begin = 0;  // the first byte after the opening quote
  std::size_t value_end = 0;    // the closing quote
};

struct XmlElementSpan {
  std::string_view name;
  int line = 0;                   // of its '<', counted as tinyxml2 counts ('\n' ends a line)
  std::size_t name_end = 0;       // just after its name in the start tag: where an attribute may go
  std::size_t start_tag_end = 0;  // just after the start tag's '>' ("/>" for an empty element)
  char quote = '"';               // the quote of its first attribute; '"' when it has none
  std::vector<XmlAttributeSpan> attributes;

  const XmlAttributeSpan* attribute(std::string_view attribute_name) const;
};

struct XmlTextMap {
  // Where text may go before the root element without changing what precedes it: after the
  // XML declaration (every "<?...?>" that starts the text after white space and a UTF-8
  // byte-order mark: tinyxml2 takes each for a declaration and refuses one after anything
  // else), else after the byte-order mark, else 0. So a byte-order mark stays first.
  std::size_t prolog_end = 0;
  bool has_declaration = false;
  std::vector<XmlElementSpan> elements;  // in document order
  // Where the document ends: the text's size, or the '<' of an end tag that closes nothing
  // (tinyxml2 stops there without an error; the URDF reader refuses such a text).
  std::size_t end = 0;
  int end_line = 0;
  // The line of the first "</a .../>", which tinyxml2 reads as an empty element a and XML does
  // not allow (the URDF reader refuses it); 0 without one.
  int sealed_end_tag_line = 0;
};

XmlTextMap map_xml_text(std::string_view text);

}  // namespace kincal::model
