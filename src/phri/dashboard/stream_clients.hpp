#pragma once
// phri::StreamClients: a crowd of dashboard clients that connect to the event stream, read a few
// frames and leave, over and over (the load of many browser tabs opening and closing). Used by the
// dashboard-load benchmark and the server's tests; each connection is a real HTTP client
// (cpp-httplib) on its own socket.
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

namespace phri {

struct StreamClientsSettings {
  std::string host = "127.0.0.1";
  int port = 0;
  std::string token;
  int connections = 100;      ///< in total, spread over the threads
  int threads = 10;           ///< connections at once, at most
  int frames_per_visit = 3;   ///< frames read before leaving
  double spread_s = 5.0;      ///< the connections are spread over about this long
  /// A visit that has not read its frames by then leaves, failed: the server's keep-alive pings
  /// would hold it open for ever once the loop stops publishing (the read timeout never fires).
  double visit_timeout_s = 5.0;
};

class StreamClients {
public:
  explicit StreamClients(const StreamClientsSettings& settings);
  ~StreamClients();  ///< join()
  StreamClients(const StreamClients&) = delete;
  StreamClients& operator=(const StreamClients&) = delete;

  /// Waits until every connection has come and gone.
  void join();
  /// Connections that read their frames (the others failed or were refused).
  int served() const { return served_.load(); }
  int failed() const { return failed_.load(); }

private:
  void visit_loop(int count, double gap_s);
  StreamClientsSettings settings_;
  std::vector<std::thread> threads_;
  std::atomic<int> served_{0}, failed_{0};
};

/// Resident memory of this process [kB] (/proc/self/statm).
long resident_kb();

}  // namespace phri
