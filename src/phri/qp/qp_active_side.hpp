#pragma once
// phri::QpActiveSide: where a double-sided row or bound sits in the active set.
#include <cstdint>

namespace phri {

enum class QpActiveSide : std::int8_t {
  kInactive = 0,
  kLower = 1,  // a x = l (or x = lb); multiplier <= 0
  kUpper = 2,  // a x = u (or x = ub); multiplier >= 0
};

}  // namespace phri
