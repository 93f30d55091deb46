#pragma once
// phri::SpscRing<T>: a bounded lock-free queue for exactly one producer thread and one consumer
// thread (the control thread hands log rows to the log writer, the gamepad thread hands events to
// the control thread). Slots are allocated once, at construction; push and pop copy a T into or
// out of a slot and never allocate, block or make a system call. A full ring refuses the push
// (the producer decides what to do: the logger counts a dropped row).
//
// Indices grow monotonically (64-bit: they never wrap in practice) and a slot is index & mask.
// The producer publishes a slot with a release store of head_, the consumer frees it with a
// release store of tail_; each side keeps a cached copy of the other's index so that the shared
// cache line is read only when the cached view says full (or empty).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace phri {

template <class T>
class SpscRing {
public:
  /// Capacity: `min_capacity` rounded up to a power of two (at least 2).
  explicit SpscRing(std::size_t min_capacity) {
    std::size_t capacity = 2;
    while (capacity < min_capacity) capacity *= 2;
    slots_ = std::make_unique<T[]>(capacity);
    mask_ = capacity - 1;
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const { return mask_ + 1; }

  // ---- producer thread only
  /// Copies `item` into the ring; false (nothing written) when the ring is full.
  bool try_push(const T& item) noexcept {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - cached_tail_ > mask_) {
      cached_tail_ = tail_.load(std::memory_order_acquire);
      if (head - cached_tail_ > mask_) return false;
    }
    slots_[head & mask_] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  /// Number of items in the ring as the producer sees it right after its last push (an upper
  /// bound of the true depth: the consumer may have taken some since).
  std::size_t depth_after_push() const noexcept {
    return static_cast<std::size_t>(head_.load(std::memory_order_relaxed) - tail_.load(std::memory_order_acquire));
  }

  // ---- consumer thread only
  /// Copies the oldest item into `out` and frees its slot; false when the ring is empty.
  bool try_pop(T& out) noexcept {
    const T* item = front();
    if (item == nullptr) return false;
    out = *item;
    pop_front();
    return true;
  }
  /// The oldest item, read in place (valid until pop_front()), or nullptr when empty.
  const T* front() noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == cached_head_) {
      cached_head_ = head_.load(std::memory_order_acquire);
      if (tail == cached_head_) return nullptr;
    }
    return &slots_[tail & mask_];
  }
  /// Frees the slot front() returned.
  void pop_front() noexcept { tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

  // ---- any thread
  /// Items in the ring at some instant during the call.
  std::size_t size_approx() const noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    return head >= tail ? static_cast<std::size_t>(head - tail) : 0;
  }

private:
  static constexpr std::size_t kLine = 64;  // keep the two sides' indices on separate cache lines
  std::unique_ptr<T[]> slots_;
  std::size_t mask_ = 0;
  alignas(kLine) std::atomic<std::uint64_t> head_{0};  // next slot to write (producer)
  std::uint64_t cached_tail_ = 0;                      // producer's view of tail_
  alignas(kLine) std::atomic<std::uint64_t> tail_{0};  // next slot to read (consumer)
  std::uint64_t cached_head_ = 0;                      // consumer's view of head_
};

}  // namespace phri
