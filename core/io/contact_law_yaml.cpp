#include "core/io/contact_law_yaml.hpp"

#include <algorithm>

#include "core/common/error.hpp"

namespace demcal::io {
namespace {

contact::SlotSpec read_slot(const YamlNode& node) {
  contact::SlotSpec slot;
  slot.model = node["model"].as_string();
  for (const auto& key : node.keys())
    if (key != "model") slot.params[key] = node[key].as_number();
  return slot;
}

}  // namespace

contact::ContactLawSpec read_contact_law_spec(const YamlNode& node) {
  node.expect_only({"normal", "cohesion", "tangential", "rolling"});
  contact::ContactLawSpec spec;
  spec.normal = read_slot(node["normal"]);
  spec.tangential = read_slot(node["tangential"]);
  if (auto c = node.child("cohesion")) spec.cohesion = read_slot(*c);
  if (auto r = node.child("rolling")) spec.rolling = read_slot(*r);
  return spec;
}

contact::ContactLaw read_contact_law(const YamlNode& node) {
  const contact::ContactLawSpec spec = read_contact_law_spec(node);
  const std::string base = node.path().empty() ? "contact_law" : node.path();
  try {
    return contact::ContactLaw::from_spec(spec, base);
  } catch (const InputError& e) {
    // from_spec names the bad field by its path below `base` ("contact_law.normal.k2_ratio");
    // report the line of that field (or of its deepest existing parent), not of the section.
    if (e.where().rfind(base, 0) != 0) throw;
    const std::string rest = e.where().substr(base.size());
    YamlNode at = node;
    std::size_t pos = 0;
    while (pos < rest.size() && rest[pos] == '.') {
      const std::size_t next = std::min(rest.find('.', pos + 1), rest.size());
      const auto child = at.child(rest.substr(pos + 1, next - pos - 1));
      if (!child) break;
      at = *child;
      pos = next;
    }
    std::string what = e.what();
    if (what.rfind(e.where() + ": ", 0) == 0) what = what.substr(e.where().size() + 2);
    throw InputError(at.where() + rest.substr(pos), what);
  }
}

}  // namespace demcal::io
