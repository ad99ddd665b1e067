#include "core/io/contact_law_yaml.hpp"

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
  return contact::ContactLaw::from_spec(read_contact_law_spec(node), node.where());
}

}  // namespace demcal::io
