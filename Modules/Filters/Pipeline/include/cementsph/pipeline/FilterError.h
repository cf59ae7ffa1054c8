// How the CementSPH pipeline filters report a failure (as vtkSPHInjectionFilter does): the outputs are left
// empty, ErrorEvent fires with the one-line message, and the message and exception are kept for the caller
// (GetErrorMessage, RethrowIfFailed). No VTK error print: a command-line program says it once, its own way.
#pragma once

#include <exception>
#include <string>

class vtkObject;

namespace cementsph::pipeline {

class FilterError {
public:
  void clear() {
    message_.clear();
    error_ = nullptr;
  }
  // Call from a catch block: keeps the current exception and fires ErrorEvent on `filter`.
  void keepCurrent(vtkObject* filter);
  const std::string& message() const { return message_; }
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

private:
  std::string message_;
  std::exception_ptr error_;
};

} // namespace cementsph::pipeline
