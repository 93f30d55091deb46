#include "logged_qps.hpp"

#include <phri/core/error.hpp>

#include <zstd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <fstream>
#include <iterator>
#include <utility>

namespace phri {
namespace {

static_assert(std::endian::native == std::endian::little, "the file is little-endian and read by memcpy");

constexpr std::array<char, 8> kMagic = {'P', 'H', 'R', 'I', 'Q', 'P', 'L', 'G'};
constexpr std::size_t kHeaderBytes = 72;
// Far more than any controller's QP: the sizes are checked before anything is allocated from them.
constexpr std::uint32_t kMaxDimension = 4096;
constexpr std::uint64_t kMaxPayloadBytes = std::uint64_t{1} << 32;

Eigen::Index lower_triangle_size(Eigen::Index n) { return n * (n + 1) / 2; }
// The c-th entry of a lower triangle stored row by row (numpy.tril_indices' order): (0,0), (1,0), (1,1), (2,0), ...
std::pair<Eigen::Index, Eigen::Index> lower_triangle_entry(Eigen::Index c) {
  Eigen::Index row = 0;
  while (lower_triangle_size(row + 1) <= c) ++row;
  return {row, c - lower_triangle_size(row)};
}
Eigen::Index sides_width(const LoggedQps& q) { return q.m_in + q.n; }

// The width of every float64 array, in the file's order (bench/data/README.md).
std::array<Eigen::Index, 10> float_widths(const LoggedQps& q) {
  return {lower_triangle_size(q.n), q.n, q.m_eq * q.n, q.m_eq, q.m_in * q.n, q.m_in, q.m_in, q.n, q.n, q.n};
}

std::uint64_t payload_size(const LoggedQps& q, std::uint64_t ticks) {
  std::uint64_t per_tick = 4 + 1 + 1 + 1 + 4 + 2 * static_cast<std::uint64_t>(sides_width(q));
  for (const Eigen::Index w : float_widths(q)) per_tick += 8 * static_cast<std::uint64_t>(w);
  return kHeaderBytes + ticks * per_tick;
}

// ---------------------------------------------------------------------------- writing

class PayloadWriter {
public:
  template <class T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  // One float64 array [ticks, width] (value(t, c)): each value's bits XOR the previous tick's at
  // the same column, split into 8 byte planes (least significant first), each plane column by
  // column, tick by tick. Smooth signals then have long runs of zero bytes in their high planes.
  template <class Value>
  void put_floats(std::size_t ticks, Eigen::Index width, Value value) {
    std::vector<std::uint64_t> delta(ticks * static_cast<std::size_t>(width));
    for (Eigen::Index c = 0; c < width; ++c) {
      std::uint64_t previous = 0;
      for (std::size_t t = 0; t < ticks; ++t) {
        const auto bits = std::bit_cast<std::uint64_t>(static_cast<double>(value(t, c)));
        delta[static_cast<std::size_t>(c) * ticks + t] = bits ^ previous;
        previous = bits;
      }
    }
    for (int plane = 0; plane < 8; ++plane) {
      for (const std::uint64_t d : delta) bytes_.push_back(static_cast<std::uint8_t>(d >> (8 * plane)));
    }
  }
  std::vector<std::uint8_t>& bytes() { return bytes_; }

private:
  std::vector<std::uint8_t> bytes_;
};

void put_header(PayloadWriter& w, const LoggedQps& q) {
  for (const char c : kMagic) w.put(c);
  w.put(LoggedQps::kVersion);
  for (const Eigen::Index d : {q.n, q.m_eq, q.m_in}) w.put(static_cast<std::uint32_t>(d));
  w.put(static_cast<std::uint32_t>(q.ticks.size()));
  w.put(q.session_cycles);
  w.put(q.session_solves);
  w.put(q.stride);
  w.put(static_cast<std::int32_t>(q.settings.max_iterations));
  w.put(std::uint32_t{0});
  w.put(q.settings.feasibility_tolerance);
  w.put(q.settings.dependence_tolerance);
  w.put(q.settings.infinity);
}

void put_sides(PayloadWriter& w, const std::vector<QpActiveSide>& rows, const std::vector<QpActiveSide>& bounds) {
  for (const QpActiveSide s : rows) w.put(static_cast<std::int8_t>(s));
  for (const QpActiveSide s : bounds) w.put(static_cast<std::int8_t>(s));
}

std::vector<std::uint8_t> encode(const LoggedQps& q) {
  PayloadWriter w;
  put_header(w, q);
  const auto& ticks = q.ticks;
  for (const LoggedQpTick& t : ticks) w.put(t.cycle);
  for (const LoggedQpTick& t : ticks) {
    w.put(static_cast<std::uint8_t>((t.options.warm_start ? 1 : 0) | (t.options.reuse_hessian_factor ? 2 : 0)));
  }
  for (const LoggedQpTick& t : ticks) w.put(t.solves);
  for (const LoggedQpTick& t : ticks) w.put(static_cast<std::uint8_t>(t.status));
  for (const LoggedQpTick& t : ticks) w.put(t.iterations);
  for (const LoggedQpTick& t : ticks) put_sides(w, t.warm_rows, t.warm_bounds);
  for (const LoggedQpTick& t : ticks) put_sides(w, t.final_rows, t.final_bounds);
  const std::size_t T = ticks.size();
  const Eigen::Index n = q.n;
  w.put_floats(T, lower_triangle_size(n), [&](std::size_t t, Eigen::Index c) {
    const auto [i, j] = lower_triangle_entry(c);
    return ticks[t].problem.H(i, j);
  });
  w.put_floats(T, n, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.g[c]; });
  w.put_floats(T, q.m_eq * n, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.A_eq(c / n, c % n); });
  w.put_floats(T, q.m_eq, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.b_eq[c]; });
  w.put_floats(T, q.m_in * n, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.A(c / n, c % n); });
  w.put_floats(T, q.m_in, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.l[c]; });
  w.put_floats(T, q.m_in, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.u[c]; });
  w.put_floats(T, n, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.lb[c]; });
  w.put_floats(T, n, [&](std::size_t t, Eigen::Index c) { return ticks[t].problem.ub[c]; });
  w.put_floats(T, n, [&](std::size_t t, Eigen::Index c) { return ticks[t].x[c]; });
  return std::move(w.bytes());
}

// Every tick's vectors sized as the file's dimensions say (the writer's input is checked, the
// reader's output sized here).
bool tick_has_sizes(const LoggedQps& q, const LoggedQpTick& t) {
  const auto s = [](const std::vector<QpActiveSide>& v) { return static_cast<Eigen::Index>(v.size()); };
  const QpProblem& p = t.problem;
  return s(t.warm_rows) == q.m_in && s(t.final_rows) == q.m_in && s(t.warm_bounds) == q.n && s(t.final_bounds) == q.n &&
         p.H.rows() == q.n && p.H.cols() == q.n && p.g.size() == q.n && p.A_eq.rows() == q.m_eq &&
         p.A_eq.cols() == q.n && p.b_eq.size() == q.m_eq && p.A.rows() == q.m_in && p.A.cols() == q.n &&
         p.l.size() == q.m_in && p.u.size() == q.m_in && p.lb.size() == q.n && p.ub.size() == q.n && t.x.size() == q.n;
}

// ---------------------------------------------------------------------------- reading

class PayloadReader {
public:
  PayloadReader(const std::vector<std::uint8_t>& bytes, std::size_t offset) : bytes_(bytes), offset_(offset) {}
  template <class T>
  T get() {
    T value;
    std::memcpy(&value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  // The inverse of PayloadWriter::put_floats: calls set(t, c, value) for every value.
  template <class Set>
  void get_floats(std::size_t ticks, Eigen::Index width, Set set) {
    const std::size_t count = ticks * static_cast<std::size_t>(width);
    const std::uint8_t* planes = bytes_.data() + offset_;
    offset_ += 8 * count;
    for (Eigen::Index c = 0; c < width; ++c) {
      std::uint64_t bits = 0;
      for (std::size_t t = 0; t < ticks; ++t) {
        const std::size_t k = static_cast<std::size_t>(c) * ticks + t;
        std::uint64_t delta = 0;
        for (int plane = 0; plane < 8; ++plane) delta |= std::uint64_t{planes[plane * count + k]} << (8 * plane);
        bits ^= delta;
        set(t, c, std::bit_cast<double>(bits));
      }
    }
  }

private:
  const std::vector<std::uint8_t>& bytes_;
  std::size_t offset_;
};

std::vector<std::uint8_t> decompress(const std::vector<std::uint8_t>& file, const std::string& name) {
  constexpr std::array<std::uint8_t, 4> kZstdMagic = {0x28, 0xb5, 0x2f, 0xfd};
  if (file.size() < kZstdMagic.size() || !std::equal(kZstdMagic.begin(), kZstdMagic.end(), file.begin())) {
    throw IoError(name, "not a logged-QP file (not a zstd frame)");
  }
  const std::uint64_t size = ZSTD_getFrameContentSize(file.data(), file.size());
  if (size == ZSTD_CONTENTSIZE_ERROR) throw IoError(name, "truncated or corrupted: no complete zstd frame header");
  if (size == ZSTD_CONTENTSIZE_UNKNOWN) throw IoError(name, "truncated or corrupted: the zstd frame states no size");
  if (size > kMaxPayloadBytes) throw IoError(name, "corrupted: the zstd frame states " + std::to_string(size) + " bytes");
  std::vector<std::uint8_t> payload(size);
  const std::size_t n = ZSTD_decompress(payload.data(), payload.size(), file.data(), file.size());
  if (ZSTD_isError(n)) throw IoError(name, std::string("truncated or corrupted (zstd: ") + ZSTD_getErrorName(n) + ")");
  if (n != size) throw IoError(name, "corrupted: the zstd frame decompressed to " + std::to_string(n) + " bytes, not its stated size");
  return payload;
}

// The header's dimensions and settings into `q`; returns the tick count after the size checks.
std::size_t read_header(const std::vector<std::uint8_t>& payload, const std::string& name, LoggedQps& q) {
  if (payload.size() < kHeaderBytes || !std::equal(kMagic.begin(), kMagic.end(), payload.begin())) {
    throw IoError(name, "not a logged-QP file (no PHRIQPLG header)");
  }
  PayloadReader r(payload, kMagic.size());
  if (const auto version = r.get<std::uint32_t>(); version != LoggedQps::kVersion) {
    throw IoError(name, "format version " + std::to_string(version) + ", this build reads version " +
                            std::to_string(LoggedQps::kVersion) + " (re-record it: phri_record_qps)");
  }
  const auto n = r.get<std::uint32_t>(), m_eq = r.get<std::uint32_t>(), m_in = r.get<std::uint32_t>();
  const auto ticks = r.get<std::uint32_t>();
  if (n == 0 || n > kMaxDimension || m_eq > kMaxDimension || m_in > kMaxDimension) {
    throw IoError(name, "corrupted: sizes n " + std::to_string(n) + ", m_eq " + std::to_string(m_eq) + ", m_in " + std::to_string(m_in));
  }
  q.n = n;
  q.m_eq = m_eq;
  q.m_in = m_in;
  q.session_cycles = r.get<std::uint32_t>();
  q.session_solves = r.get<std::uint32_t>();
  q.stride = r.get<std::uint32_t>();
  q.settings.max_iterations = r.get<std::int32_t>();
  r.get<std::uint32_t>();
  q.settings.feasibility_tolerance = r.get<double>();
  q.settings.dependence_tolerance = r.get<double>();
  q.settings.infinity = r.get<double>();
  if (const std::uint64_t expected = payload_size(q, ticks); payload.size() != expected) {
    throw IoError(name, "sizes do not add up: " + std::to_string(ticks) + " ticks of n " + std::to_string(n) + ", m_eq " +
                            std::to_string(m_eq) + ", m_in " + std::to_string(m_in) + " need " + std::to_string(expected) +
                            " bytes, the file holds " + std::to_string(payload.size()));
  }
  return ticks;
}

std::vector<QpActiveSide> get_sides(PayloadReader& r, Eigen::Index count, const std::string& name) {
  std::vector<QpActiveSide> sides(static_cast<std::size_t>(count));
  for (QpActiveSide& s : sides) {
    const auto value = r.get<std::int8_t>();
    if (value < 0 || value > 2) throw IoError(name, "corrupted: active side " + std::to_string(value));
    s = static_cast<QpActiveSide>(value);
  }
  return sides;
}

void decode_ticks(PayloadReader& r, const std::string& name, LoggedQps& q) {
  auto& ticks = q.ticks;
  for (LoggedQpTick& t : ticks) {
    t.problem.resize(q.n, q.m_eq, q.m_in);
    t.x.resize(q.n);
  }
  for (LoggedQpTick& t : ticks) t.cycle = r.get<std::uint32_t>();
  for (LoggedQpTick& t : ticks) {
    const auto flags = r.get<std::uint8_t>();
    t.options = {.warm_start = (flags & 1) != 0, .reuse_hessian_factor = (flags & 2) != 0};
  }
  for (LoggedQpTick& t : ticks) t.solves = r.get<std::uint8_t>();
  for (LoggedQpTick& t : ticks) {
    const auto status = r.get<std::uint8_t>();
    if (status > static_cast<std::uint8_t>(QpStatus::kNumericalError)) throw IoError(name, "corrupted: status " + std::to_string(status));
    t.status = static_cast<QpStatus>(status);
  }
  for (LoggedQpTick& t : ticks) t.iterations = r.get<std::int32_t>();
  for (LoggedQpTick& t : ticks) {
    t.warm_rows = get_sides(r, q.m_in, name);
    t.warm_bounds = get_sides(r, q.n, name);
  }
  for (LoggedQpTick& t : ticks) {
    t.final_rows = get_sides(r, q.m_in, name);
    t.final_bounds = get_sides(r, q.n, name);
  }
  const std::size_t T = ticks.size();
  const Eigen::Index n = q.n;
  r.get_floats(T, lower_triangle_size(n), [&](std::size_t t, Eigen::Index c, double v) {
    const auto [i, j] = lower_triangle_entry(c);
    ticks[t].problem.H(i, j) = v;
  });
  r.get_floats(T, n, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.g[c] = v; });
  r.get_floats(T, q.m_eq * n, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.A_eq(c / n, c % n) = v; });
  r.get_floats(T, q.m_eq, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.b_eq[c] = v; });
  r.get_floats(T, q.m_in * n, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.A(c / n, c % n) = v; });
  r.get_floats(T, q.m_in, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.l[c] = v; });
  r.get_floats(T, q.m_in, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.u[c] = v; });
  r.get_floats(T, n, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.lb[c] = v; });
  r.get_floats(T, n, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].problem.ub[c] = v; });
  r.get_floats(T, n, [&](std::size_t t, Eigen::Index c, double v) { ticks[t].x[c] = v; });
}

}  // namespace

void write_logged_qps(const std::string& path, const LoggedQps& qps, int zstd_level) {
  for (const LoggedQpTick& t : qps.ticks) {
    if (!tick_has_sizes(qps, t)) throw IoError(path, "tick of cycle " + std::to_string(t.cycle) + " has other sizes than n, m_eq, m_in");
  }
  const std::vector<std::uint8_t> payload = encode(qps);
  std::vector<std::uint8_t> frame(ZSTD_compressBound(payload.size()));
  ZSTD_CCtx* context = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(context, ZSTD_c_compressionLevel, zstd_level);
  ZSTD_CCtx_setParameter(context, ZSTD_c_checksumFlag, 1);  // a flipped byte is an error, not other numbers
  const std::size_t size = ZSTD_compress2(context, frame.data(), frame.size(), payload.data(), payload.size());
  ZSTD_freeCCtx(context);
  if (ZSTD_isError(size)) throw IoError(path, std::string("zstd: ") + ZSTD_getErrorName(size));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(frame.data()), static_cast<std::streamsize>(size));
  if (!out.flush()) throw IoError(path, "cannot write");
}

LoggedQps parse_logged_qps(const std::vector<std::uint8_t>& file_bytes, const std::string& name) {
  const std::vector<std::uint8_t> payload = decompress(file_bytes, name);
  LoggedQps q;
  q.ticks.resize(read_header(payload, name, q));
  PayloadReader r(payload, kHeaderBytes);
  decode_ticks(r, name, q);
  return q;
}

LoggedQps read_logged_qps(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open (record it: phri_record_qps, bench/data/README.md)");
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  return parse_logged_qps(bytes, path);
}

QpSolveOptions prepare_replay(const LoggedQpTick& tick, QpSolver& solver, bool warm) {
  solver.set_active_set(tick.warm_rows, tick.warm_bounds);
  if (tick.options.reuse_hessian_factor) solver.set_hessian(tick.problem.H);
  QpSolveOptions options = tick.options;
  options.warm_start = options.warm_start && warm;
  return options;
}

}  // namespace phri
