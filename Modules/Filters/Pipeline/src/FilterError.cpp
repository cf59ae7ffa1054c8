#include "cementsph/pipeline/FilterError.h"

#include <vtkCommand.h>
#include <vtkObject.h>

#include <stdexcept>

namespace cementsph::pipeline {

void FilterError::keepCurrent(vtkObject* filter) {
  error_ = std::current_exception();
  try {
    std::rethrow_exception(error_);
  } catch (const std::exception& e) {
    message_ = e.what();
  } catch (...) {
    message_ = "unknown error";
  }
  filter->InvokeEvent(vtkCommand::ErrorEvent, const_cast<char*>(message_.c_str()));
}

} // namespace cementsph::pipeline
