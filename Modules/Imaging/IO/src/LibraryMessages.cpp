#include "cementsph/imaging/LibraryMessages.h"

#include <gdcmTrace.h>
#include <itkObject.h>
#include <itkOutputWindow.h>
#include <vtkObject.h>
#include <vtkOutputWindow.h>

#include <cctype>
#include <cstdio>
#include <iostream>
#include <unistd.h>

namespace cementsph::imaging {

namespace {
bool verboseMessages = true;
}

void setLibraryMessagesVerbose(bool verbose) {
  verboseMessages = verbose;
  itk::Object::SetGlobalWarningDisplay(verbose);
  vtkObject::SetGlobalWarningDisplay(verbose ? 1 : 0);
  gdcm::Trace::SetWarning(verbose);
  gdcm::Trace::SetError(verbose);
  gdcm::Trace::SetDebug(false); // GDCM's debug trace is for GDCM's developers, even with --verbose
}

bool libraryMessagesVerbose() { return verboseMessages; }

StderrCapture::StderrCapture() {
  std::cerr.flush();
  std::fflush(stderr);
  FILE* f = std::tmpfile();
  if (!f) return; // no capture: messages go to stderr as they would anyway
  savedFd_ = ::dup(2);
  if (savedFd_ < 0 || ::dup2(::fileno(f), 2) < 0) {
    if (savedFd_ >= 0) ::close(savedFd_);
    savedFd_ = -1;
    std::fclose(f);
    return;
  }
  file_ = f;
}

std::string StderrCapture::release() {
  if (!file_) return {};
  std::cerr.flush();
  std::fflush(stderr);
  ::dup2(savedFd_, 2);
  ::close(savedFd_);
  savedFd_ = -1;
  FILE* f = static_cast<FILE*>(file_);
  file_ = nullptr;
  std::string text;
  std::rewind(f);
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0 && text.size() < (1u << 20)) text.append(buffer, n);
  std::fclose(f);
  if (verboseMessages && !text.empty()) std::cerr << text; // --verbose: the libraries' words, as before
  return text;
}

StderrCapture::~StderrCapture() { (void)release(); }

std::string oneLine(std::string text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  for (auto& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

} // namespace cementsph::imaging
