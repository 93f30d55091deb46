#include <phri/dashboard/stream_clients.hpp>

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <string_view>

#include <unistd.h>

namespace phri {

StreamClients::StreamClients(const StreamClientsSettings& settings) : settings_(settings) {
  const int threads = std::max(1, std::min(settings.threads, settings.connections));
  const int per_thread = settings.connections / threads, extra = settings.connections % threads;
  for (int t = 0; t < threads; ++t) {
    const int count = per_thread + (t < extra ? 1 : 0);
    const double gap = count > 0 ? settings.spread_s / count : 0.0;
    threads_.emplace_back([this, count, gap] { visit_loop(count, gap); });
  }
}

StreamClients::~StreamClients() { join(); }

void StreamClients::join() {
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
}

// One connection after the other: open the stream, read the frames, hang up, wait for the next.
void StreamClients::visit_loop(int count, double gap_s) {
  const std::string path = "/api/stream?token=" + settings_.token;
  for (int i = 0; i < count; ++i) {
    const auto start = std::chrono::steady_clock::now();
    httplib::Client client(settings_.host, settings_.port);
    client.set_read_timeout(3, 0);
    client.set_connection_timeout(3, 0);  // httplib waits 300 s by default
    client.set_write_timeout(3, 0);
    int frames = 0;
    const auto deadline = start + std::chrono::duration<double>(settings_.visit_timeout_s);
    client.Get(path, [&](const char* data, std::size_t size) {
      const std::string_view chunk(data, size);
      for (std::size_t at = chunk.find("data:"); at != std::string_view::npos; at = chunk.find("data:", at + 5)) ++frames;
      // false: leave (the connection is closed)
      return frames < settings_.frames_per_visit && std::chrono::steady_clock::now() < deadline;
    });
    if (frames >= settings_.frames_per_visit) {
      ++served_;
    } else {
      ++failed_;
    }
    std::this_thread::sleep_until(start + std::chrono::duration<double>(gap_s));
  }
}

long resident_kb() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

}  // namespace phri
