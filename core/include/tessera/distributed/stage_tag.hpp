#pragma once
// Messages of the certified sequence (solve -> certify -> escape -> solve at rank r+1 -> ...)
// carry their stage in the `phase` field: phase = stage * kStagePhaseStride + step, where step
// is the stage's own protocol step. Stage 0 is the first solve, so a run without certification
// sends exactly the phases of RoundProtocol. Fast agents may send next-stage messages while slow
// ones finish the current stage; the stage tells the receiver to keep them for later.
//
// Steps >= kAuxiliaryStepBase are reserved for the transport's own exchanges after the sequence
// (the DDS round loop's distributed rounding).

#include <cstdint>

namespace tessera {

constexpr std::uint32_t kStagePhaseStride = 1000;
constexpr std::uint32_t kAuxiliaryStepBase = 100;

/// What a stage does: stage s is kind s % 3. A refinement skips the escape stage's number
/// (certify s -> solve s + 2), so the rank is r0 + the number of escapes so far.
enum class StageKind : std::uint32_t { kSolve = 0, kCertify = 1, kEscape = 2 };

inline std::uint32_t stage_of_phase(std::uint32_t phase) {
  return phase / kStagePhaseStride;
}
inline std::uint32_t step_of_phase(std::uint32_t phase) {
  return phase % kStagePhaseStride;
}
inline std::uint32_t tag_phase(std::uint32_t stage, std::uint32_t step) {
  return stage * kStagePhaseStride + step;
}
inline StageKind stage_kind(std::uint32_t stage) {
  return static_cast<StageKind>(stage % 3);
}
/// True for the transport's messages after the sequence (not the agent's business).
inline bool is_auxiliary_phase(std::uint32_t phase) {
  return step_of_phase(phase) >= kAuxiliaryStepBase;
}

}  // namespace tessera
