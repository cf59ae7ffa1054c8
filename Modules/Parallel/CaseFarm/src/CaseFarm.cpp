#include "cementsph/parallel/CaseFarm.h"

#include <algorithm>
#include <memory>

namespace cementsph::parallel {

std::unique_ptr<CaseFarm> makeMpiCaseFarm(); // MpiCaseFarm.cpp

namespace {

class SerialCaseFarm final : public CaseFarm {
public:
  int rank() const override { return 0; }
  int ranks() const override { return 1; }
  void agree(const std::function<void()>& setup) override { setup(); }
  void run(std::size_t n, const Work& work, const OnOutcome& onOutcome) override { runCasesHere(n, work, onOutcome); }
  int threadsPerRank(int coresOnNode) const override { return std::max(1, coresOnNode); }
};

} // namespace

void runCasesHere(std::size_t n, const CaseFarm::Work& work, const CaseFarm::OnOutcome& onOutcome) {
  for (std::size_t i = 0; i < n; ++i) {
    CaseOutcome outcome;
    outcome.index = i;
    try {
      outcome.payload = work(i);
    } catch (const std::invalid_argument&) {
      throw; // bad input: no case can get past it
    } catch (const std::exception& e) {
      outcome.ok = false;
      outcome.payload = e.what();
    }
    onOutcome(outcome);
  }
}

CaseFarm& caseFarm() {
  static std::unique_ptr<CaseFarm> farm =
      launchedByMpi() ? makeMpiCaseFarm() : std::unique_ptr<CaseFarm>(std::make_unique<SerialCaseFarm>());
  return *farm;
}

} // namespace cementsph::parallel
