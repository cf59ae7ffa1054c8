#include "cementsph/rendering/VirtualDisplay.h"

#include <X11/Xlib.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <mutex>
#include <poll.h>
#include <signal.h>
#include <stdexcept>
#include <string>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace cementsph::rendering {
namespace {

constexpr int kStartTimeoutMs = 10000;

std::mutex gMutex;
// The DISPLAY value known to work: an outside server that opened, or our Xvfb.
std::string gSettledDisplay;
pid_t gXvfbPid = -1;
// Only the process that started Xvfb may stop it: a forked child (e.g. a gtest death test) that exits
// must not take the parent's display away.
pid_t gOwnerPid = -1;
// Held open for the whole run. Xvfb runs with -terminate, so when this process dies in any way (even
// SIGKILL, when no atexit handler runs) the kernel closes this last connection and Xvfb exits by itself.
Display* gKeepAlive = nullptr;

bool canOpenDisplay(const char* name) {
  if (name == nullptr || *name == '\0') return false;
  Display* display = XOpenDisplay(name);
  if (display == nullptr) return false;
  XCloseDisplay(display);
  return true;
}

std::string findOnPath(const std::string& program) {
  const char* pathEnv = std::getenv("PATH");
  const std::string path = pathEnv != nullptr ? pathEnv : "/usr/local/bin:/usr/bin:/bin";
  std::size_t begin = 0;
  while (begin <= path.size()) {
    std::size_t end = path.find(':', begin);
    if (end == std::string::npos) end = path.size();
    const std::string dir = end > begin ? path.substr(begin, end - begin) : ".";
    const std::string candidate = dir + "/" + program;
    struct stat info {};
    if (stat(candidate.c_str(), &info) == 0 && S_ISREG(info.st_mode) &&
        access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
    begin = end + 1;
  }
  return {};
}

void reapWithin(pid_t pid, std::chrono::milliseconds patience) {
  const auto deadline = std::chrono::steady_clock::now() + patience;
  while (std::chrono::steady_clock::now() < deadline) {
    const pid_t r = waitpid(pid, nullptr, WNOHANG);
    if (r == pid || (r < 0 && errno != EINTR)) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
}

void stopVirtualServer() {
  if (gXvfbPid <= 0 || getpid() != gOwnerPid) return;
  if (gKeepAlive != nullptr) {
    XCloseDisplay(gKeepAlive);
    gKeepAlive = nullptr;
  }
  kill(gXvfbPid, SIGTERM);
  reapWithin(gXvfbPid, std::chrono::milliseconds(2000));
  gXvfbPid = -1;
}

std::string describeExit(int status) {
  if (WIFEXITED(status)) {
    if (WEXITSTATUS(status) == 127) return "could not be executed";
    return "exited with status " + std::to_string(WEXITSTATUS(status));
  }
  if (WIFSIGNALED(status)) return "was killed by signal " + std::to_string(WTERMSIG(status));
  return "stopped unexpectedly";
}

[[noreturn]] void failStart(pid_t pid, const std::string& what) {
  int status = 0;
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  throw std::runtime_error("cementsph rendering: no X display and the virtual one (Xvfb) " + what +
                           "; try running 'Xvfb :99 &' and 'export DISPLAY=:99' by hand to see why");
}

// Reads the display number Xvfb writes on the -displayfd pipe once it accepts connections.
// Returns an empty string if Xvfb closed the pipe (died) first; throws on timeout.
std::string readDisplayNumber(int readFd, pid_t pid) {
  std::string text;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(kStartTimeoutMs);
  while (text.find('\n') == std::string::npos) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      close(readFd);
      failStart(pid, "did not report a display within " + std::to_string(kStartTimeoutMs / 1000) + " s");
    }
    pollfd waitFor{readFd, POLLIN, 0};
    const int ready = poll(&waitFor, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue; // timeout is handled at the top of the loop
    char chunk[64];
    const ssize_t n = read(readFd, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    text.append(chunk, static_cast<std::size_t>(n));
  }
  close(readFd);
  std::string digits;
  for (char c : text) {
    if (c >= '0' && c <= '9') digits += c;
    else if (!digits.empty()) break;
  }
  return digits;
}

// Returns the DISPLAY string of the started server.
std::string startVirtualServer() {
  const std::string xvfb = findOnPath("Xvfb");
  if (xvfb.empty()) {
    throw std::runtime_error(
        "cementsph rendering: no X display and Xvfb is not installed; install the 'xvfb' package "
        "(scripts/install-deps.sh does) or set DISPLAY to a running X server");
  }

  int fds[2];
  if (pipe(fds) != 0) {
    throw std::runtime_error(std::string("cementsph rendering: pipe() failed: ") + std::strerror(errno));
  }
  // Keep the write end away from 0..2, which the child replaces with /dev/null.
  if (fds[1] <= 2) {
    const int high = fcntl(fds[1], F_DUPFD, 3);
    close(fds[1]);
    fds[1] = high;
  }
  fcntl(fds[0], F_SETFD, FD_CLOEXEC);

  // Everything the child needs is prepared before fork(): between fork and exec in a possibly
  // multi-threaded program only async-signal-safe calls are allowed.
  std::vector<std::string> args = {xvfb,         "-displayfd", std::to_string(fds[1]), "-screen", "0",
                                    "1920x1080x24", "-nolisten",  "tcp",                  "-terminate"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  // Xvfb's start-up chatter (xkbcomp warnings, socket-directory notes) would clutter every program's output.
  const int devNull = open("/dev/null", O_RDWR | O_CLOEXEC);

  const pid_t pid = fork();
  if (pid < 0) {
    const int err = errno;
    close(fds[0]);
    close(fds[1]);
    if (devNull >= 0) close(devNull);
    throw std::runtime_error(std::string("cementsph rendering: fork() failed: ") + std::strerror(err));
  }
  if (pid == 0) {
    if (devNull >= 0) {
      dup2(devNull, STDIN_FILENO);
      dup2(devNull, STDOUT_FILENO);
      dup2(devNull, STDERR_FILENO);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(fds[1]);
  if (devNull >= 0) close(devNull);

  const std::string number = readDisplayNumber(fds[0], pid);
  if (number.empty()) {
    int status = 0;
    waitpid(pid, &status, 0);
    throw std::runtime_error("cementsph rendering: no X display and the virtual one (Xvfb, " + xvfb + ") " +
                             describeExit(status) + " before reporting a display; run 'Xvfb :99' by "
                             "hand to see why");
  }
  const std::string display = ":" + number;
  Display* keepAlive = XOpenDisplay(display.c_str());
  if (keepAlive == nullptr) failStart(pid, "started on " + display + " but refuses connections");

  gXvfbPid = pid;
  gOwnerPid = getpid();
  gKeepAlive = keepAlive;
  static bool registered = false;
  if (!registered) {
    std::atexit(stopVirtualServer);
    registered = true;
  }
  setenv("DISPLAY", display.c_str(), 1);
  return display;
}

} // namespace

void VirtualDisplay::ensureDisplay() {
  // A mutex rather than std::call_once: besides starting Xvfb at most once, every call re-checks that
  // DISPLAY still names the display we settled on (code in between may have unset or changed it, and VTK
  // would abort on a bad one). After the first call this is a string comparison, no X round trip.
  // A throwing attempt leaves nothing settled, so a later call tries again.
  std::lock_guard<std::mutex> lock(gMutex);
  const char* current = std::getenv("DISPLAY");
  if (gXvfbPid > 0) {
    if (current == nullptr || gSettledDisplay != current) setenv("DISPLAY", gSettledDisplay.c_str(), 1);
    return;
  }
  if (current != nullptr && !gSettledDisplay.empty() && gSettledDisplay == current) return;
  if (canOpenDisplay(current)) {
    gSettledDisplay = current;
    return;
  }
  gSettledDisplay = startVirtualServer();
}

std::string VirtualDisplay::displayName() {
  const char* name = std::getenv("DISPLAY");
  return name != nullptr ? name : "";
}

bool VirtualDisplay::startedVirtualServer() {
  std::lock_guard<std::mutex> lock(gMutex);
  return gXvfbPid > 0;
}

} // namespace cementsph::rendering
