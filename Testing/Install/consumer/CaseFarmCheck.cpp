// The case farm (Parallel, linked with MPI): outside an MPI launch the cases run in this process, each
// outcome in index order; case i returns i^2, so the payloads sum to 0^2 + ... + 9^2 = 9 * 10 * 19 / 6 = 285.
#include "Checks.h"

#include "cementsph/parallel/CaseFarm.h"

#include <string>

int checkCaseFarm() {
  double sum = 0.0;
  std::size_t outcomes = 0;
  auto& farm = cementsph::parallel::caseFarm();
  farm.run(10, [](std::size_t i) { return std::to_string(i * i); },
           [&](const cementsph::parallel::CaseOutcome& outcome) {
             sum += std::stod(outcome.payload);
             ++outcomes;
           });
  return compare("case farm, sum of i^2 over 10 cases", sum, 9.0 * 10.0 * 19.0 / 6.0, 0.0) +
         compare("case farm, outcomes", static_cast<double>(outcomes), 10.0, 0.0);
}
