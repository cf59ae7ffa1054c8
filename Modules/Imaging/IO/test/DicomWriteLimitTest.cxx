// The DICOM writer against a file size limit (issue 21): GDCM asserts (SIGABRT) when a slice's write fails part
// way, so writeDicomSeries checks the room first. Portable in a test: a fork()ed child ignores SIGXFSZ (a write
// past the limit then fails with EFBIG instead of killing the process), lowers RLIMIT_FSIZE to a few kB and
// writes a small series; it reports through its exit status and a pipe, and the parent asserts: an OutputError
// of one line naming the folder and the limit, no signal, and no series (nor staging folder) left behind.
//
// Oracle for the limit: a slice file holds at least its pixels (32 x 32 int16 = 2048 bytes) plus the 128-byte
// preamble and "DICM" (PS3.10 section 7.1), 2180 bytes; a limit of 2179 bytes fits no slice whatever the header,
// so any write attempt would meet EFBIG. A limit of 1 MiB fits each (a few tags over the pixels).
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace cementsph::imaging;

constexpr int kEdge = 32;                             // voxels per slice edge
constexpr long kPixelBytes = long(kEdge) * kEdge * 2; // int16
constexpr long kPreambleBytes = 128 + 4;              // PS3.10 7.1: preamble and "DICM"

ImageType::Pointer smallCt(int slices) {
  auto img = ImageType::New();
  ImageType::SizeType size{{kEdge, kEdge, itk::SizeValueType(slices)}};
  img->SetRegions(ImageType::RegionType(size));
  img->Allocate();
  img->FillBuffer(400.0f);
  return img;
}

// What the child saw.
struct ChildReport {
  int status = -1;     // 0 OutputError, 1 another exception, 2 no exception; -1 if it did not exit (a signal)
  int signal = 0;      // the signal that ended it, if any
  std::string message; // the exception's text
};

// Writes a `slices`-slice series into `folder` in a child under RLIMIT_FSIZE = limitBytes, SIGXFSZ ignored.
ChildReport writeUnderLimit(const fs::path& folder, int slices, rlim_t limitBytes) {
  int channel[2];
  if (pipe(channel) != 0) ADD_FAILURE() << "pipe: " << std::strerror(errno);
  const pid_t pid = fork();
  if (pid == 0) {
    close(channel[0]);
    signal(SIGXFSZ, SIG_IGN);
    rlimit limit{};
    getrlimit(RLIMIT_FSIZE, &limit);
    limit.rlim_cur = limitBytes;
    if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(3);
    int status = 2;
    std::string message;
    try {
      writeDicomSeries(smallCt(slices), folder.string(), -1024.0);
    } catch (const OutputError& e) {
      status = 0, message = e.what();
    } catch (const std::exception& e) {
      status = 1, message = e.what();
    }
    // A pipe is not a file: the size limit does not apply to it.
    if (!message.empty() && write(channel[1], message.data(), message.size()) < 0) status = 4;
    close(channel[1]);
    _exit(status); // no atexit handlers, no gtest teardown in the child
  }
  close(channel[1]);
  ChildReport report;
  char buffer[4096];
  for (ssize_t n; (n = read(channel[0], buffer, sizeof buffer)) > 0;) report.message.append(buffer, std::size_t(n));
  close(channel[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFEXITED(status)) report.status = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) report.signal = WTERMSIG(status);
  return report;
}

class DicomWriteLimitTest : public ::testing::Test {
protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("dicom_limit_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  std::size_t entries(const fs::path& folder) const {
    std::size_t n = 0;
    for (auto it = fs::directory_iterator(folder); it != fs::directory_iterator(); ++it) ++n;
    return n;
  }
  fs::path root_;
};

} // namespace

TEST_F(DicomWriteLimitTest, ASliceOverTheFileSizeLimitIsOneLineAndLeavesNoSeries) {
  const rlim_t limit = kPixelBytes + kPreambleBytes - 1; // 2179 bytes: no slice fits
  const fs::path folder = root_ / "new" / "series";
  const ChildReport r = writeUnderLimit(folder, 3, limit);
  ASSERT_EQ(r.signal, 0) << "the child was killed by signal " << r.signal << " (" << strsignal(r.signal) << ")";
  ASSERT_EQ(r.status, 0) << "status " << r.status << ": " << r.message;
  EXPECT_EQ(r.message.find('\n'), std::string::npos) << r.message;
  EXPECT_NE(r.message.find(folder.string()), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("file size limit"), std::string::npos) << r.message;
  // Nothing behind: not the series, not its staging folder, not the parent the writer had to create.
  EXPECT_FALSE(fs::exists(root_ / "new"));
  EXPECT_EQ(entries(root_), 0u);
}

// An earlier series in the folder stays as it was when the new one cannot be written.
TEST_F(DicomWriteLimitTest, AFailedWriteLeavesAnEarlierSeriesAsItWas) {
  const fs::path folder = root_ / "series";
  writeDicomSeries(smallCt(2), folder.string(), -1024.0);
  ASSERT_EQ(entries(folder), 2u);
  const auto before = fs::file_size(folder / "slice0000.dcm");
  const ChildReport r = writeUnderLimit(folder, 4, kPixelBytes + kPreambleBytes - 1);
  ASSERT_EQ(r.signal, 0) << strsignal(r.signal);
  ASSERT_EQ(r.status, 0) << r.message;
  EXPECT_EQ(entries(folder), 2u);
  EXPECT_EQ(fs::file_size(folder / "slice0000.dcm"), before);
  EXPECT_EQ(entries(root_), 1u); // the folder only: no staging folder left
}

// Under a limit every slice fits, the series is written: the check does not refuse what can be written.
TEST_F(DicomWriteLimitTest, UnderALimitEverySliceFitsTheSeriesIsWritten) {
  const rlim_t limit = 1 << 20;
  const fs::path folder = root_ / "series";
  const ChildReport r = writeUnderLimit(folder, 3, limit);
  ASSERT_EQ(r.signal, 0) << strsignal(r.signal);
  ASSERT_EQ(r.status, 2) << r.message;
  ASSERT_EQ(entries(folder), 3u);
  for (const char* name : {"slice0000.dcm", "slice0001.dcm", "slice0002.dcm"}) {
    const auto bytes = fs::file_size(folder / name);
    EXPECT_GE(bytes, std::uintmax_t(kPixelBytes + kPreambleBytes)) << name;
    EXPECT_LE(bytes, std::uintmax_t(limit)) << name;
  }
  EXPECT_EQ(entries(root_), 1u);
}

// A shorter series written over a longer one replaces it whole: no slice of the old one is left to mix in.
TEST_F(DicomWriteLimitTest, AShorterSeriesReplacesALongerOneWhole) {
  const fs::path folder = root_ / "series";
  writeDicomSeries(smallCt(5), folder.string(), -1024.0);
  ASSERT_EQ(entries(folder), 5u);
  writeDicomSeries(smallCt(2), folder.string(), -1024.0);
  EXPECT_EQ(entries(folder), 2u);
  EXPECT_EQ(readVolume(folder.string())->GetLargestPossibleRegion().GetSize()[2], 2u);
}
