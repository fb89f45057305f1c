#include "transport/participant_tags.hpp"

#include <sstream>

namespace tessera::transport {

namespace {
constexpr const char* kMagic = "tessera-tags";
// A GUID prefix prints as 12 hex bytes joined by dots (at most 35 characters); a list of
// more than kMaxReplaced of them is not one of ours.
constexpr std::size_t kMaxPrefix = 40;
}  // namespace

std::vector<std::uint8_t> ParticipantTags::encode() const {
  if (!udp_only && !retiring && replaces.empty()) return {};
  std::string text = kMagic;
  if (udp_only) text += ";udp_only=1";
  if (retiring) text += ";retiring=1";
  for (std::size_t k = 0; k < replaces.size() && k < kMaxReplaced; ++k)
    text += (k == 0 ? ";replaces=" : ",") + replaces[k];
  return std::vector<std::uint8_t>(text.begin(), text.end());
}

ParticipantTags ParticipantTags::decode(const std::vector<std::uint8_t>& bytes) {
  ParticipantTags tags;
  const std::string text(bytes.begin(), bytes.end());
  std::istringstream in(text);
  std::string field;
  if (!std::getline(in, field, ';') || field != kMagic) return tags;
  while (std::getline(in, field, ';')) {
    const std::size_t eq = field.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = field.substr(0, eq), value = field.substr(eq + 1);
    if (key == "udp_only") {
      tags.udp_only = value == "1";
    } else if (key == "retiring") {
      tags.retiring = value == "1";
    } else if (key == "replaces") {
      std::vector<std::string> list;
      std::istringstream items(value);
      std::string item;
      bool ok = true;
      while (std::getline(items, item, ','))
        ok = ok && !item.empty() && item.size() <= kMaxPrefix && list.size() < kMaxReplaced &&
             (list.push_back(item), true);
      if (ok) tags.replaces = list;  // a malformed list is ignored as a whole
    }
  }
  return tags;
}

}  // namespace tessera::transport
