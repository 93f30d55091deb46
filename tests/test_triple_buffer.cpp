// ctest-labels: unit
// core/triple_buffer.hpp: the latest-value hand-off between one writer and one reader thread.
//   Single thread: the initial value, the newest of several publishes, a value read twice.
//   Two threads: a writer publishing records whose fields all equal a counter, a reader checking
//   every value it sees is whole (no torn record), never older than the last one it saw, and that
//   it sees the final value; the reader allocates nothing.
#include <phri/core/triple_buffer.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

namespace {

struct Record {
  std::array<std::uint64_t, 16> fields{};  // larger than a word: a torn copy would show
};

Record record(std::uint64_t n) {
  Record r;
  r.fields.fill(n);
  return r;
}

TEST(TripleBuffer, GivesTheInitialValueThenTheNewestPublished) {
  phri::TripleBuffer<int> buffer(7);
  EXPECT_EQ(buffer.latest(), 7);
  buffer.publish(1);
  buffer.publish(2);
  buffer.publish(3);
  EXPECT_EQ(buffer.latest(), 3);
  EXPECT_EQ(buffer.latest(), 3);  // nothing new: the same value again
  buffer.back() = 4;
  EXPECT_EQ(buffer.latest(), 3);  // written, not yet published
  buffer.publish();
  EXPECT_EQ(buffer.latest(), 4);
}

TEST(TripleBuffer, AReaderThreadNeverSeesATornOrOlderValue) {
  // The writer goes on until it has published kLast records and the reader has read a while
  // alongside (on a loaded machine the writer could otherwise finish before the reader starts).
  constexpr std::uint64_t kLast = 200000;
  constexpr std::uint64_t kConcurrentReads = 1000;
  phri::TripleBuffer<Record> buffer(record(0));
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> reads_seen{0}, last_published{0};
  std::thread writer([&] {
    std::uint64_t n = 0;
    while (n < kLast || reads_seen.load() < kConcurrentReads) buffer.publish(record(++n));
    last_published.store(n);
    done.store(true);
  });
  std::uint64_t newest = 0, reads = 0, torn = 0, backwards = 0;
  phri::test::AllocationCounter count;
  for (;;) {
    const bool writer_done = done.load();
    const Record& r = buffer.latest();
    reads_seen.store(++reads);
    for (std::uint64_t f : r.fields) torn += f != r.fields[0] ? 1 : 0;
    backwards += r.fields[0] < newest ? 1 : 0;
    newest = r.fields[0];
    if (writer_done) break;
  }
  EXPECT_EQ(count.allocations(), 0u);
  writer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(newest, last_published.load());
  EXPECT_GE(newest, kLast);
  EXPECT_GT(reads, kConcurrentReads);
}

}  // namespace
