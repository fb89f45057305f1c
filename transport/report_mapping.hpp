#pragma once
// Agent 0's reports (core/runtime/agent_report.hpp) and their wire form (idl/tessera.idl
// AgentReport, topic kReportTopic): field for field, one union branch per report. Decoding
// throws TransportError on a report kind or certificate method it does not know.

#include <cstdint>
#include <string>

#include "runtime/agent_report.hpp"
#include "tessera.h"
#include "transport/transport_error.hpp"

namespace tessera::transport {

/// Wire form of `report` from agent `sender` of run `run_id` at rollback epoch `epoch`.
wire::AgentReport to_wire_report(const agent::AgentReport& report, const std::string& run_id,
                                 std::uint32_t sender, std::uint32_t epoch);
agent::AgentReport from_wire(const wire::AgentReport& w);

}  // namespace tessera::transport
