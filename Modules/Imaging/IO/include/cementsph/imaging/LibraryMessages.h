// What GDCM, ITK and VTK print on their own. Their warnings and errors (GDCM's "Unknown VR", ITK's
// missing-tool notes, VTK's reader errors) bury the one line that says what went wrong, and every problem
// they report is also reported by our own checks as an exception. So they are silenced unless the user
// asks for --verbose, when they pass through to stderr as before.
#pragma once

#include <string>

namespace cementsph::imaging {

// Silences (verbose = false) or restores (true) the libraries' message output. Call once at start-up.
void setLibraryMessagesVerbose(bool verbose);
bool libraryMessagesVerbose();

// Collects everything written to the process's stderr (file descriptor 2: C stdio, std::cerr, and the C
// libraries under ITK such as nifti_io, which write with fprintf) while it lives. Not thread-safe: use it
// around sequential reads only. release() restores stderr and returns the text.
class StderrCapture {
public:
  StderrCapture();
  ~StderrCapture();
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;
  // Restores stderr and returns what was written meanwhile (once; later calls return "").
  std::string release();

private:
  int savedFd_ = -1;
  void* file_ = nullptr; // FILE*
};

// Text made into one line: trailing white space dropped, line breaks turned into spaces.
std::string oneLine(std::string text);

} // namespace cementsph::imaging
