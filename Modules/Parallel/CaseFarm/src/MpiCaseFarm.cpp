// The MPI farm of CaseFarm.h: rank 0 hands out case indices and collects results; workers compute.
// Messages (MPI_COMM_WORLD, bytes): kTask (rank 0 -> worker: the case index, 8 bytes), kStop (no more
// cases), kAbort (the job stops: FarmStopped), kResult (worker -> rank 0: index, kind, payload), kSetup
// (worker -> rank 0: why its set-up failed). Rank 0 waits by polling with short sleeps rather than in a
// blocking receive, which in Open MPI spins a core: on a node whose cores all run workers that would take
// a core from them.
#include "cementsph/parallel/CaseFarm.h"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

namespace cementsph::parallel {

namespace {

enum Tag : int { kTask = 101, kStop, kAbort, kResult, kSetup };
enum Kind : std::uint8_t { kOk = 0, kFailed = 1, kBadInput = 2 };

void finaliseAtExit() {
  int initialised = 0, finalised = 0;
  MPI_Initialized(&initialised);
  MPI_Finalized(&finalised);
  if (initialised && !finalised) MPI_Finalize();
}

// Probes until a message matching (source, tag) is there, sleeping between probes; returns its status.
MPI_Status waitForMessage(int source, int tag) {
  MPI_Status status;
  auto pause = std::chrono::microseconds(50);
  for (;;) {
    int flag = 0;
    MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, &status);
    if (flag) return status;
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(2000));
  }
}

std::string receiveBytes(const MPI_Status& probed) {
  int count = 0;
  MPI_Get_count(&probed, MPI_BYTE, &count);
  std::string bytes(std::size_t(count), '\0');
  MPI_Status status;
  MPI_Recv(bytes.data(), count, MPI_BYTE, probed.MPI_SOURCE, probed.MPI_TAG, MPI_COMM_WORLD, &status);
  return bytes;
}

void sendBytes(const std::string& bytes, int to, int tag) {
  if (bytes.size() > std::size_t(INT_MAX)) throw std::runtime_error("a case's result is over 2 GB: too large to send");
  MPI_Send(bytes.data(), int(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

void sendIndex(std::size_t index, int to) {
  const std::uint64_t i = index;
  MPI_Send(&i, 8, MPI_BYTE, to, kTask, MPI_COMM_WORLD);
}

void sendEmpty(int to, int tag) { MPI_Send(nullptr, 0, MPI_BYTE, to, tag, MPI_COMM_WORLD); }

class MpiCaseFarm final : public CaseFarm {
public:
  MpiCaseFarm() {
    int initialised = 0;
    MPI_Initialized(&initialised);
    if (!initialised) {
      int provided = 0;
      MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
      std::atexit(finaliseAtExit);
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
    // Ranks on this node (sharing memory), and whether the coordinator is one of them.
    MPI_Comm node;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
    int onNode = 1, coordinatorHere = rank_ == 0 ? 1 : 0, coordinatorOnNode = 0;
    MPI_Comm_size(node, &onNode);
    MPI_Allreduce(&coordinatorHere, &coordinatorOnNode, 1, MPI_INT, MPI_MAX, node);
    MPI_Comm_free(&node);
    computingOnNode_ = ranks_ > 1 ? onNode - coordinatorOnNode : 1;
  }

  int rank() const override { return rank_; }
  int ranks() const override { return ranks_; }
  int threadsPerRank(int cores) const override { return std::max(1, cores / std::max(1, computingOnNode_)); }

  void agree(const std::function<void()>& setup) override {
    std::exception_ptr failure;
    std::string message;
    bool badInput = false;
    try {
      setup();
    } catch (const std::invalid_argument& e) {
      failure = std::current_exception();
      message = e.what();
      badInput = true;
    } catch (const std::exception& e) {
      failure = std::current_exception();
      message = e.what();
    }
    const int mine = failure ? rank_ : INT_MAX;
    int first = INT_MAX;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == INT_MAX) return;
    if (rank_ == 0 && first == 0) std::rethrow_exception(failure);
    if (rank_ == first) sendBytes(std::string(1, char(badInput)) + message, 0, kSetup);
    if (rank_ != 0) throw FarmStopped("stopped: rank " + std::to_string(first) + " could not set up");
    const std::string reply = receiveBytes(waitForMessage(first, kSetup));
    const std::string text = "rank " + std::to_string(first) + ": " + reply.substr(1);
    if (reply[0]) throw std::invalid_argument(text);
    throw std::runtime_error(text);
  }

  void run(std::size_t n, const Work& work, const OnOutcome& onOutcome) override {
    if (ranks_ == 1) return runCasesHere(n, work, onOutcome);
    if (rank_ == 0) coordinate(n, onOutcome);
    else serve(work);
  }

private:
  void coordinate(std::size_t n, const OnOutcome& onOutcome) {
    std::vector<std::optional<CaseOutcome>> done(n);
    std::size_t next = 0, delivered = 0;
    int busy = 0;
    std::exception_ptr error;
    auto handOut = [&](int worker) {
      if (!error && next < n) {
        sendIndex(next++, worker);
        ++busy;
      } else {
        sendEmpty(worker, error ? kAbort : kStop);
      }
    };
    for (int w = 1; w < ranks_; ++w) handOut(w);
    while (busy > 0) {
      const MPI_Status probed = waitForMessage(MPI_ANY_SOURCE, kResult);
      const std::string bytes = receiveBytes(probed);
      --busy;
      CaseOutcome outcome;
      std::uint64_t index = 0;
      std::memcpy(&index, bytes.data(), 8);
      outcome.index = std::size_t(index);
      outcome.rank = probed.MPI_SOURCE;
      const auto kind = static_cast<Kind>(bytes[8]);
      outcome.ok = kind == kOk;
      outcome.payload = bytes.substr(9);
      if (kind == kBadInput && !error)
        error = std::make_exception_ptr(std::invalid_argument("rank " + std::to_string(outcome.rank) + ": " + outcome.payload));
      if (outcome.index < n) done[outcome.index] = std::move(outcome);
      handOut(probed.MPI_SOURCE);
      while (!error && delivered < n && done[delivered]) {
        try {
          onOutcome(*done[delivered]);
        } catch (...) {
          error = std::current_exception();
        }
        done[delivered].reset(); // its payload is no longer needed
        ++delivered;
      }
    }
    if (error) std::rethrow_exception(error);
  }

  void serve(const Work& work) {
    // A test of failing ranks (Applications/cementsph/test/MpiTest): every case sent to this rank fails.
    const char* failRank = std::getenv("CEMENTSPH_FAIL_RANK");
    const bool fail = failRank && std::to_string(rank_) == failRank;
    for (;;) {
      MPI_Status probed;
      MPI_Probe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &probed);
      const std::string message = receiveBytes(probed);
      if (probed.MPI_TAG == kStop) return;
      if (probed.MPI_TAG == kAbort) throw FarmStopped("stopped by rank 0");
      std::uint64_t index = 0;
      std::memcpy(&index, message.data(), 8);
      std::string reply(9, '\0');
      std::memcpy(reply.data(), &index, 8);
      try {
        reply[8] = char(kOk);
        if (fail)
          throw std::runtime_error(std::string("failed on purpose (CEMENTSPH_FAIL_RANK=") + failRank +
                                   ", a test of failing ranks)");
        reply += work(std::size_t(index));
      } catch (const std::invalid_argument& e) {
        reply.resize(9);
        reply[8] = char(kBadInput);
        reply += e.what();
      } catch (const std::exception& e) {
        reply.resize(9);
        reply[8] = char(kFailed);
        reply += e.what();
      }
      sendBytes(reply, 0, kResult);
    }
  }

  int rank_ = 0, ranks_ = 1, computingOnNode_ = 1;
};

} // namespace

std::unique_ptr<CaseFarm> makeMpiCaseFarm() { return std::make_unique<MpiCaseFarm>(); }

} // namespace cementsph::parallel
