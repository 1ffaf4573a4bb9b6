// libFuzzer target for the URDF reader and `kincal urdf --original`'s writer (issue #25). The
// input is a URDF's text; seeds are the real URDFs of ../shared/realdata/urdf-corpus.
//   - The text map (urdf_text.hpp) of every text tinyxml2 parses agrees with tinyxml2: the same
//     elements in document order, with the same names, lines and attributes (names; values where
//     tinyxml2 keeps them as written: no entity, no line end).
//   - parse_urdf_chain (default chain): either InputError or a chain; model_from_urdf likewise.
//   - For a model: its forward kinematics equal the URDF's (1e-9 m relative, 1e-9 rad), and
//     write_calibrated_urdf of that same model writes a URDF the reader reads back
//     to the same chain (joint names and types), and the text is the input's with kincal's
//     comment and nothing else changed (no origin moved by more than urdf.cpp's kUnchangedM).
// Any other exception, a crash, a leak or undefined behaviour is a finding. Runs standalone too
// (file arguments), and as the ctest fuzz.urdf for a bounded time.
#include <tinyxml2.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "host/model/urdf.hpp"
#include "host/model/urdf_chain.hpp"
#include "host/model/urdf_text.hpp"

using namespace kincal;

namespace {

// A property that must hold; the line that failed on stderr, then abort (libFuzzer keeps the input).
void require(bool condition, int line = __builtin_LINE()) {
  if (condition) return;
  std::fprintf(stderr, "urdf_fuzz.cpp:%d: property failed\n", line);
  std::abort();
}

void check_text_map(const std::string& text) {
  if (text.find('\0') != std::string::npos) return;
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.c_str(), text.size()) != tinyxml2::XML_SUCCESS) return;
  const model::XmlTextMap map = model::map_xml_text(text);
  std::size_t k = 0;
  for (const tinyxml2::XMLElement* e = doc.FirstChildElement(); e != nullptr; ++k) {
    require(k < map.elements.size());
    const model::XmlElementSpan& span = map.elements[k];
    require(span.name == e->Name() && span.line == e->GetLineNum());
    std::size_t a = 0;
    for (const tinyxml2::XMLAttribute* attribute = e->FirstAttribute(); attribute != nullptr;
         attribute = attribute->Next(), ++a) {
      require(a < span.attributes.size() && span.attributes[a].name == attribute->Name());
      const std::string_view raw(text.data() + span.attributes[a].value_begin,
                                 span.attributes[a].value_end - span.attributes[a].value_begin);
      if (raw.find_first_of("&\r\n") == std::string_view::npos) require(raw == attribute->Value());
    }
    require(a == span.attributes.size());
    const tinyxml2::XMLElement* next = e->FirstChildElement();
    for (const tinyxml2::XMLElement* up = e; next == nullptr && up != nullptr;
         up = up->Parent() != nullptr ? up->Parent()->ToElement() : nullptr)
      next = up->NextSiblingElement();
    e = next;
  }
  require(k == map.elements.size());
}

void check_round_trip(const std::string& text) {
  model::UrdfChain chain;
  model::RobotModel m;
  try {
    chain = model::parse_urdf_chain(text, "fuzz.urdf");
    m = model::model_from_urdf(chain);
  } catch (const model::InputError&) {
    return;
  }
  // The model's kinematics equal the URDF's. (Where two axes nearly intersect, a common normal
  // of ~1e-9 m, axes.cpp once took the normal's direction from the difference of two foot points
  // and the frames were ~1e-7 rad off: urdf_regressions/nearly_intersecting_axes.urdf.)
  const std::vector<double> half(static_cast<std::size_t>(m.joint_count()), 0.5);
  const model::Transform urdf_tool = model::urdf_link_poses(chain, half).back(),
                         tool = model::forward_kinematics(m, half);
  if ((urdf_tool.translation - tool.translation).norm() > 1e-9 * (1.0 + urdf_tool.translation.norm()) ||
      (urdf_tool.rotation - tool.rotation).cwiseAbs().maxCoeff() > 1e-9)
    std::abort();
  model::CalibratedUrdf out;
  try {
    out = model::write_calibrated_urdf(text, "fuzz.urdf", {chain.base_link, chain.tip_link}, m);
  } catch (const model::InputError&) {
    return;  // a chain kincal's conventions cannot express (checked by the model's own tests)
  }
  // What kincal writes it reads (an InputError here escapes and is a finding), the same chain.
  const model::UrdfChain again = model::parse_urdf_chain(out.text, "again.urdf", {chain.base_link, chain.tip_link});
  require(again.joints.size() == chain.joints.size());
  for (std::size_t k = 0; k < chain.joints.size(); ++k)
    require(again.joints[k].name == chain.joints[k].name && again.joints[k].type == chain.joints[k].type);
  // The same model written back changes no origin (each within 1e-11 of what it was): the text
  // is the input's with kincal's comment at the end of the prolog, every other byte kept.
  const std::size_t at = model::map_xml_text(text).prolog_end;
  require(out.text.size() > text.size());
  const std::size_t comment = out.text.size() - text.size();
  require(out.text.compare(0, at, text, 0, at) == 0);
  require(out.text.compare(at + comment, std::string::npos, text, at, std::string::npos) == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  check_text_map(text);
  check_round_trip(text);
  return 0;
}
