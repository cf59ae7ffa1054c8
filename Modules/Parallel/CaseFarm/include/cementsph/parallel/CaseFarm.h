// Where the cases of a study or a plan run (issue "Planning at scale", item 2): here, one after another, or
// spread over the ranks of an MPI job (`mpirun -n N cementsph study ...`, or `srun` under Slurm).
//
// Rank 0 coordinates: it hands each worker rank the next case as soon as that rank is free (dynamic
// scheduling: cases differ in cost by 10x and more), gets the result back and passes the outcomes to the
// caller in case order, so a report built from them is the same, row for row, as a serial run's. Workers
// only compute; only rank 0 writes files. Each rank runs its case with its own OpenMP threads.
//
// A case's work returns its result as bytes (the caller's encoding). If it throws:
//   std::invalid_argument  bad input that no case can get past (a tip in solid, a bad scene): the whole job
//                          stops, and rank 0 throws it (as a serial run throws it), naming the rank;
//   anything else          that case failed (CaseOutcome::ok false, with the reason and the rank); the other
//                          cases go on. Serial runs follow the same rule, so the two agree.
// A rank that dies (a signal, an abort) takes the job with it, as MPI does; the tables the caller rewrote
// after every outcome keep what was done.
//
// MPI is used only when an MPI launcher started this process (its environment has OMPI_COMM_WORLD_SIZE,
// PMIX_RANK or PMI_SIZE); otherwise no MPI call is made and everything runs in this process (ranks() 1).
#pragma once

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>

namespace cementsph::parallel {

struct CaseOutcome {
  std::size_t index = 0;
  int rank = 0;          // the rank that ran the case (0 in a serial run)
  bool ok = true;        // false: the work threw (payload is the reason)
  std::string payload;   // the work's result, or why it failed
};

// Thrown on a worker rank when the job stops (bad input found on some rank, or rank 0 stopped): the worker
// has nothing to report, rank 0 reports it.
class FarmStopped : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

class CaseFarm {
public:
  using Work = std::function<std::string(std::size_t index)>;
  using OnOutcome = std::function<void(const CaseOutcome&)>;

  virtual ~CaseFarm() = default;
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  // Ranks that run cases: every rank but the coordinator, or this process alone.
  int workers() const { return ranks() > 1 ? ranks() - 1 : 1; }
  bool coordinator() const { return rank() == 0; }

  // Every rank calls agree() with the same set-up (read the inputs, check them). If it threw anywhere, it
  // throws everywhere: on rank 0 the lowest failing rank's exception (its type kept for invalid_argument,
  // its message prefixed "rank N: " when N is not 0), on the workers FarmStopped.
  virtual void agree(const std::function<void()>& setup) = 0;

  // Every rank calls run() with the same n. On rank 0: every case's outcome, in index order, to onOutcome,
  // which may write reports; returns when all are in. On a worker: runs the cases it is sent and returns
  // when rank 0 has none left. If onOutcome throws, or a case threw std::invalid_argument, the workers are
  // stopped (each finishes its case) and the exception leaves run() on rank 0 (FarmStopped on the workers).
  virtual void run(std::size_t n, const Work& work, const OnOutcome& onOutcome) = 0;

  // OpenMP threads for this rank when the user chose none: the node's cores shared among the ranks that
  // compute on it (the coordinator, which mostly waits, not counted), at least 1.
  virtual int threadsPerRank(int coresOnNode) const = 0;
};

// The farm of this process: MPI's when an MPI launcher started it, else a serial one. The first call
// initialises MPI (MPI_Init_thread, funneled); it is finalised at exit.
CaseFarm& caseFarm();

// Whether an MPI launcher started this process, and its rank there (0 when none did), read from the
// launcher's environment without starting MPI: main() leaves error lines to rank 0.
bool launchedByMpi();
int launchedRank();

// The serial farm (every case here, in order), also what an MPI job of one rank runs.
void runCasesHere(std::size_t n, const CaseFarm::Work& work, const CaseFarm::OnOutcome& onOutcome);

} // namespace cementsph::parallel
