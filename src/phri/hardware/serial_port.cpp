#include <phri/hardware/serial_port.hpp>

#include <phri/core/error.hpp>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

namespace phri {
namespace {

std::string open_failure_reason(int error) {
  const std::string text = std::strerror(error);
  switch (error) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return text + " (is the sensor plugged in and powered? see ls /dev/serial/by-id/)";
    case EACCES:
    case EPERM:
      return text + " (serial devices belong to group dialout: sudo usermod -aG dialout $USER, then log in again)";
    case EBUSY:
      return text + " (another program has the port open)";
    default:
      return text;
  }
}

}  // namespace

unsigned int serial_speed_constant(int baud) noexcept {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    default: return 0;
  }
}

SerialPort::SerialPort(const std::string& device, int baud) : device_(device) {
  const speed_t speed = serial_speed_constant(baud);
  if (speed == 0) throw IoError(device, "unsupported baud rate " + std::to_string(baud));
  fd_ = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) throw IoError(device, "cannot open: " + open_failure_reason(errno));
  termios tio{};
  if (::tcgetattr(fd_, &tio) != 0) {
    const int error = errno;
    ::close(fd_);
    throw IoError(device, std::string("not a serial device: ") + std::strerror(error));
  }
  ::cfmakeraw(&tio);                       // no echo, no line editing, no character translation
  tio.c_cflag |= CLOCAL | CREAD;           // ignore modem lines, enable the receiver
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS);  // 8N1, no hardware flow control
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);        // binary data: no XON/XOFF
  tio.c_cc[VMIN] = 0;                      // reads never block (poll() does the waiting)
  tio.c_cc[VTIME] = 0;
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 || ::tcsetattr(fd_, TCSANOW, &tio) != 0) {
    const int error = errno;
    ::close(fd_);
    throw IoError(device, std::string("cannot configure the port (raw, ") + std::to_string(baud) +
                              " baud): " + std::strerror(error));
  }
  // One owner: a second program opening the sensor would steal half of its bytes (it gets EBUSY).
  if (::ioctl(fd_, TIOCEXCL) != 0) {
    const int error = errno;
    ::close(fd_);
    throw IoError(device, std::string("cannot take exclusive access: ") + std::strerror(error));
  }
  ::tcflush(fd_, TCIOFLUSH);
}

SerialPort::~SerialPort() {
  if (fd_ < 0) return;
  ::ioctl(fd_, TIOCNXCL);  // the device may stay open elsewhere (a pty's other end): let us reopen it
  ::close(fd_);
}

SerialResult SerialPort::read_some(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) noexcept {
  pollfd pfd{fd_, POLLIN, 0};
  const int ready = ::poll(&pfd, 1, timeout_ms);
  if (ready < 0) return errno == EINTR ? SerialResult{} : SerialResult{SerialStatus::kClosed, 0, errno};
  if (ready == 0) return {};
  // Read before looking at POLLHUP: bytes that arrived before the hang-up are still data.
  const ssize_t n = ::read(fd_, buffer, capacity);
  if (n > 0) return {SerialStatus::kData, static_cast<std::size_t>(n), 0};
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
    if (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) return {SerialStatus::kClosed, 0, 0};
    return {};
  }
  return {SerialStatus::kClosed, 0, n < 0 ? errno : 0};  // n == 0: end of file
}

SerialResult SerialPort::write_all(std::string_view bytes, int timeout_ms) noexcept {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + written, bytes.size() - written);
    if (n > 0) {
      written += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) return {SerialStatus::kClosed, written, errno};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return {SerialStatus::kTimeout, written, 0};
    pollfd pfd{fd_, POLLOUT, 0};
    if (::poll(&pfd, 1, static_cast<int>(left)) > 0 && (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)))
      return {SerialStatus::kClosed, written, 0};
  }
  return {SerialStatus::kData, written, 0};
}

void SerialPort::discard_input() noexcept { ::tcflush(fd_, TCIFLUSH); }

}  // namespace phri
