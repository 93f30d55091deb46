#pragma once
// phri::TripleBuffer<T>: the newest value of something one thread produces and one other thread
// reads, handed over without locks and without either side ever waiting (the F/T reader thread
// hands wrenches to the control cycle). Unlike SpscRing, older values are overwritten: the reader
// always gets the latest one.
//
// Three slots: the writer owns one (back), the reader owns one (front), the third (middle) is the
// hand-off. publish() swaps back and middle with one atomic exchange and marks the middle fresh;
// the reader swaps front and middle only when the middle is fresh. Each slot is touched by one
// thread at a time, and the acquire/release exchange orders the slot's contents with the swap, so
// T may be any copyable type (no torn reads). Nothing allocates after construction.
#include <array>
#include <atomic>
#include <cstdint>

namespace phri {

template <class T>
class TripleBuffer {
public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) { slots_.fill(initial); }
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // ---- writer thread only
  /// The slot the writer fills before publish() (keeps what was written there two publishes ago).
  T& back() noexcept { return slots_[back_]; }
  /// Hands back() to the reader; the writer gets the old middle slot as its new back().
  void publish() noexcept {
    const std::uint8_t old_middle = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = old_middle & kIndexMask;
  }
  void publish(const T& value) noexcept {
    back() = value;
    publish();
  }

  // ---- reader thread only
  /// The newest published value (or the initial one before any publish). Wait-free.
  const T& latest() noexcept {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      const std::uint8_t old_middle = middle_.exchange(front_, std::memory_order_acq_rel);
      front_ = old_middle & kIndexMask;
    }
    return slots_[front_];
  }

private:
  static constexpr std::uint8_t kFresh = 0x4;      // the middle slot holds a value the reader has not taken
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::size_t kLine = 64;
  std::array<T, 3> slots_{};
  alignas(kLine) std::atomic<std::uint8_t> middle_{1};
  alignas(kLine) std::uint8_t back_ = 0;   // writer's
  alignas(kLine) std::uint8_t front_ = 2;  // reader's
};

}  // namespace phri
