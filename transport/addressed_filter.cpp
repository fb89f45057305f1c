#include "transport/addressed_filter.hpp"

#include <cstdlib>
#include <cstring>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/topic/IContentFilter.hpp>
#include <fastdds/dds/topic/IContentFilterFactory.hpp>
#include <string>

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

// Reads plain CDR (Fast CDR's encoding of our final structs): primitives aligned to their
// size, counted from the end of the 4-byte encapsulation header; byte order from the header.
class CdrCursor {
 public:
  CdrCursor(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
    ok_ = size >= 4 && (data[1] == 0x00 || data[1] == 0x01);
    swap_ = ok_ && data[1] == 0x00;  // big-endian (CDR_BE); this host is little-endian
  }
  bool ok() const { return ok_; }

  std::uint32_t u32() {
    pos_ = 4 + ((pos_ - 4 + 3) & ~std::size_t{3});
    if (!ok_ || pos_ + 4 > size_) {
      ok_ = false;
      return 0;
    }
    std::uint32_t v;
    std::memcpy(&v, data_ + pos_, 4);
    pos_ += 4;
    return swap_ ? __builtin_bswap32(v) : v;
  }
  std::uint8_t u8() {
    if (!ok_ || pos_ + 1 > size_) {
      ok_ = false;
      return 0;
    }
    return data_[pos_++];
  }
  void skip_string() {
    const std::uint32_t n = u32();  // length including the terminating NUL
    if (!ok_ || n > size_ - pos_) {
      ok_ = false;
      return;
    }
    pos_ += n;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 4;
  bool ok_ = false;
  bool swap_ = false;
};

class AddressedFilter final : public dds::IContentFilter {
 public:
  AddressedFilter(AddressedLayout layout, std::uint32_t agent) : layout_(layout), agent_(agent) {}
  void set_agent(std::uint32_t agent) { agent_ = agent; }

  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&,
                const GUID_t&) const override {
    return addressed_to_agent(layout_, payload.data, payload.length, agent_);
  }

 private:
  AddressedLayout layout_;
  std::uint32_t agent_;
};

bool parse_agent(const char* text, std::uint32_t& agent) {
  if (!text || !*text) return false;
  char* end = nullptr;
  const unsigned long v = std::strtoul(text, &end, 10);
  if (*end != '\0' || v > 0xFFFFFFFFul) return false;
  agent = static_cast<std::uint32_t>(v);
  return true;
}

class AddressedFilterFactory final : public dds::IContentFilterFactory {
 public:
  ReturnCode_t create_content_filter(const char*, const char*, const dds::TopicDataType*,
                                     const char* expression, const ParameterSeq& parameters,
                                     dds::IContentFilter*& instance) override {
    std::uint32_t agent = 0;
    if (parameters.length() != 1 || !parse_agent(parameters[0], agent))
      return ReturnCode_t::RETCODE_BAD_PARAMETER;
    if (!expression) {  // new parameters for an existing filter
      if (!instance) return ReturnCode_t::RETCODE_BAD_PARAMETER;
      static_cast<AddressedFilter*>(instance)->set_agent(agent);
      return ReturnCode_t::RETCODE_OK;
    }
    AddressedLayout layout;
    if (std::strcmp(expression, addressed_expression(AddressedLayout::kHandoff)) == 0)
      layout = AddressedLayout::kHandoff;
    else if (std::strcmp(expression, addressed_expression(AddressedLayout::kBlock)) == 0)
      layout = AddressedLayout::kBlock;
    else
      return ReturnCode_t::RETCODE_BAD_PARAMETER;
    delete static_cast<AddressedFilter*>(instance);
    instance = new AddressedFilter(layout, agent);
    return ReturnCode_t::RETCODE_OK;
  }

  ReturnCode_t delete_content_filter(const char*, dds::IContentFilter* instance) override {
    delete static_cast<AddressedFilter*>(instance);
    return ReturnCode_t::RETCODE_OK;
  }
};

}  // namespace

const char* addressed_expression(AddressedLayout layout) {
  return layout == AddressedLayout::kHandoff ? "handoff" : "block";
}

bool addressed_to_agent(AddressedLayout layout, const std::uint8_t* data, std::size_t size,
                        std::uint32_t agent) {
  CdrCursor c(data, size);
  if (!c.ok()) return true;
  c.skip_string();  // run_id
  if (layout == AddressedLayout::kHandoff) {
    c.u32();  // sender
    const std::uint32_t recipient = c.u32();
    return !c.ok() || recipient == agent;
  }
  c.u32();  // round
  c.u32();  // sender
  c.u32();  // phase
  const bool broadcast = c.u8() != 0;
  if (!c.ok() || broadcast) return true;
  const std::uint32_t n = c.u32();
  for (std::uint32_t k = 0; k < n && c.ok(); ++k)
    if (c.u32() == agent) return true;
  return !c.ok();
}

bool register_addressed_filter(dds::DomainParticipant& participant) {
  // Stateless, so one factory serves every participant of the process; it must outlive them.
  static AddressedFilterFactory factory;
  if (participant.lookup_content_filter_factory(kAddressedFilterClass) != nullptr) return true;
  return participant.register_content_filter_factory(kAddressedFilterClass, &factory) ==
         ReturnCode_t::RETCODE_OK;
}

}  // namespace tessera::transport
