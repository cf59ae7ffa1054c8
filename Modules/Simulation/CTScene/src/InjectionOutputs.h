// The files of an injection (InjectionRunner.h), written by the one driver (InjectionDriver.cpp) for every
// engine (InjectionModel.h).
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/InjectionModel.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/SceneConfig.h"

#include <nlohmann/json.hpp>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace cementsph::scene::detail {

using scene::TipRecord;

// particles.pvd: (time [s], file name) of each snapshot.
std::string particleCollection(const std::vector<std::pair<double, std::string>>& snapshots);

// tip_pressure.csv. `baselinePa` is subtracted in pressure_minus_baseline_pa (0 where the pressure is physical);
// none (a model pressure whose baseline is not known yet): that column is 0.
std::string tipPressureCsv(const std::vector<TipRecord>& series, std::optional<double> baselinePa);

// The snapshots and the final files in outDir; with an empty outDir it writes nothing. Construction creates
// the folder, removes an earlier run's temporaries and numbered snapshots (AtomicFile.h) and, with the
// scene's simulated_ct_snapshots, writes simulated_ct_start.nrrd (t = 0, no cement: an X-ray sequence's
// background). A run that ends without finish() (it failed: an exception) takes its snapshots away with it,
// so a failed run leaves no partial series behind.
//
// The particle snapshots are written on a second thread while the run goes on (issue 23: 100 snapshots of a
// 5 ml run had doubled its cost when written in line). At most kQueuedSnapshots wait to be written, so memory
// stays bounded when the disk is slower than the run; a write that fails fails the run at the next snapshot or
// at finish(), with the writer's message. Engines hand over a polydata nobody else touches afterwards
// (InjectionModel::cement() builds a new one each call), so writing it on the other thread needs no copy.
class InjectionWriter {
public:
  using SimulatedCt = std::function<imaging::ImageType::Pointer()>; // the simulated CT of the state now
  using CtFrameObserver = std::function<void(double, const imaging::ImageType&)>; // InjectionRunOptions::onCtFrame
  InjectionWriter(std::string outDir, const SceneConfig& scene, double huPerRelativeDensity, SimulatedCt simulatedCt,
                  CtFrameObserver onCtFrame = {});
  ~InjectionWriter();
  InjectionWriter(const InjectionWriter&) = delete;
  InjectionWriter& operator=(const InjectionWriter&) = delete;

  bool writing() const { return !outDir_.empty(); }
  // The path of `name` in the output folder, taken as one of this run's files: if the run fails before finish()
  // ends, the destructor removes it with the snapshots, so a failed run leaves no mix of its files and an earlier
  // run's (README "Bad input", Outputs). Call it before the file is written.
  std::string fileOfThisRun(const std::string& name);
  // particles_NNNN.vtp (and simulated_ct_NNNN.nrrd: `ctNow` if given, else made) at time [s]. Give it the only
  // reference to `particles` (a moved smart pointer) while the run goes on: a reference the caller drops while
  // the writer thread writes runs VTK's garbage collector on the same objects from two threads (a crash in
  // vtkGarbageCollector::Collect, about 1 run in 40 of 5 ml, issue 23). The last one (finish) is written while
  // the caller waits, so that one may stay the caller's.
  void snapshot(double time, vtkSmartPointer<vtkPolyData> particles, const imaging::ImageType* ctNow = nullptr);
  // A snapshot as growth (InjectionModel::cementArrivedSinceLastCall): the snapshot is particles_NNNN.pvtp, the
  // union of the pieces written so far, each holding the cement that arrived over a run of snapshots. On the
  // second thread, as snapshot's: `arrived` is written as particles_piece_NNNN.vtp, and the newest pieces are
  // merged as a base-4 counter carries (four pieces of 4^j snapshots each become one of 4^(j+1),
  // particles_piece_FFFF-LLLL.vtp, snapshots FFFF to LLLL), so snapshot k names the sum of the base-4 digits
  // of k + 1 pieces (at most 3 a digit) and a voxel is written at most log4(k) + 1 times: the files grow as the
  // cement times log(snapshots), not as their product (a .pvtp naming every piece would: 2 GB of text at the
  // 10000 snapshots a scene may ask for). Base 4, not 2: half the bytes rewritten, for two more pieces a digit.
  // The same ownership rule as snapshot's.
  void snapshotPiece(double time, vtkSmartPointer<vtkPolyData> arrived, const imaging::ImageType* ctNow = nullptr);
  // The last snapshot (the final state), particles.pvd, tip_pressure.csv, simulated_ct.nrrd, scene.json,
  // sequence.json, the text files (name, content) given, then metrics.json (with the snapshot counts added).
  // simulatedCt: on the region (the last frame of the X-ray series); simulatedCtFile: simulated_ct.nrrd (the
  // input's grid, or the region's when cropped).
  void finish(double time, vtkPolyData* particles, const imaging::ImageType* simulatedCt,
              const imaging::ImageType* simulatedCtFile, const std::vector<TipRecord>& tipSeries,
              std::optional<double> baselinePa, nlohmann::json& metrics,
              const std::vector<std::pair<std::string, std::string>>& textFiles = {});

private:
  void ctFrame(double time, const std::string& ctName, const std::string& particlesName, const imaging::ImageType* now);
  // The snapshot `name` at time [s] in the series, with its simulated CT frame if the scene asks for them.
  void addSnapshot(double time, const std::string& name, const imaging::ImageType* ctNow);
  // `union_`: the path of the .pvtp this piece's snapshot is (snapshotPiece), empty for a whole snapshot.
  void queueParticles(vtkSmartPointer<vtkPolyData> particles, std::string path, std::string union_ = {});
  void writePiece(vtkSmartPointer<vtkPolyData> piece, const std::string& path, const std::string& union_); // (second thread)
  void writeQueued();           // the second thread's loop
  void waitForQueuedWrites();   // until every queued snapshot is on disk; rethrows a write's error
  void stopWriting() noexcept;  // ends the second thread (queued writes are dropped)

  static constexpr std::size_t kQueuedSnapshots = 4;
  struct QueuedPolyData {
    vtkSmartPointer<vtkPolyData> data;
    std::string path;
    std::string union_; // a piece: the snapshot's .pvtp
  };
  // The pieces the next .pvtp names, oldest first (the second thread's only): a base-4 counter's digits.
  struct Piece {
    vtkSmartPointer<vtkPolyData> data;
    std::string name;
    std::size_t first, snapshots; // the first snapshot it covers and how many
  };
  std::vector<Piece> pieces_;
  static constexpr std::size_t kMergedPieces = 4;
  std::thread writerThread_;
  std::mutex queueMutex_;
  std::condition_variable queueChanged_;
  std::deque<QueuedPolyData> queue_;
  bool writingOne_ = false, stopWriter_ = false;
  std::exception_ptr writeError_;

  std::string outDir_;
  const SceneConfig& scene_;
  double huPerRelativeDensity_;
  SimulatedCt simulatedCt_;
  CtFrameObserver onCtFrame_;
  bool ctSnapshots_ = false;
  nlohmann::json ctFrames_ = nlohmann::json::array();
  double ctSnapshotWallS_ = 0.0;
  std::vector<std::pair<double, std::string>> snapshots_;
  std::vector<std::string> written_; // this run's files (snapshots, fileOfThisRun), removed if it fails; under queueMutex_
  bool finished_ = false;
};

// The progress of a run: a line on stderr now and then (every second with an ETA on a terminal, every 30 s
// otherwise) when options.progress, and the options' callback at the first step and every 1 % of the
// injection time.
class InjectionProgress {
public:
  InjectionProgress(const InjectionRunOptions& options, std::chrono::steady_clock::time_point start, double durationS);
  // After a step that reached time t [s]; `state` says what the run holds ("674 fluid + ... , 812 steps").
  // Returns false when the callback asks the run to stop.
  bool step(double t, const std::function<std::string()>& state);
  // Ends a terminal's progress line.
  void done() const;
  double wallSeconds() const;

private:
  const InjectionRunOptions& options_;
  std::chrono::steady_clock::time_point start_;
  double duration_;
  bool tty_;
  double nextReport_ = 0.0, nextFraction_ = 0.0;
};

} // namespace cementsph::scene::detail
