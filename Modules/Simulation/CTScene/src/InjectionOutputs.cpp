#include "InjectionOutputs.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/PolyDataIO.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkAppendPolyData.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene::detail {

namespace fs = std::filesystem;
using nlohmann::json;

std::string particleCollection(const std::vector<std::pair<double, std::string>>& snapshots) {
  std::ostringstream pvd;
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [t, name] : snapshots)
    pvd << "    <DataSet timestep=\"" << std::setprecision(10) << t << "\" part=\"0\" file=\"" << name << "\"/>\n";
  pvd << "  </Collection>\n</VTKFile>\n";
  return pvd.str();
}

std::string tipPressureCsv(const std::vector<TipRecord>& series, std::optional<double> baselinePa) {
  std::ostringstream csv;
  csv << "time_s,pressure_pa,pressure_minus_baseline_pa,cannula_pressure_drop_pa,injection_pressure_pa\n"
      << std::setprecision(10);
  for (const auto& s : series)
    csv << s.time << "," << s.tipPa << "," << (baselinePa ? s.tipPa - *baselinePa : 0.0) << "," << s.cannulaPa << ","
        << s.tipPa + s.cannulaPa << "\n";
  return csv.str();
}

InjectionWriter::InjectionWriter(std::string outDir, const SceneConfig& scene, double huPerRelativeDensity,
                                 SimulatedCt simulatedCt, CtFrameObserver onCtFrame)
    : outDir_(std::move(outDir)), scene_(scene), huPerRelativeDensity_(huPerRelativeDensity),
      simulatedCt_(std::move(simulatedCt)), onCtFrame_(std::move(onCtFrame)) {
  if (!writing()) return;
  fs::create_directories(outDir_);
  // An earlier run's temporaries and snapshots must not mix with this run's (AtomicFile.h).
  imaging::removeStaleOutputs(outDir_, {"particles_####.vtp", "particles_####.pvtp", "particles_piece_####.vtp",
                                        "particles_piece_####-####.vtp",
                                        "simulated_ct_####.nrrd", "simulated_ct_start.nrrd", "sequence.json"});
  ctSnapshots_ = scene.simulatedCtSnapshots;
  if (ctSnapshots_) ctFrame(0.0, "simulated_ct_start.nrrd", "", nullptr);
}

InjectionWriter::~InjectionWriter() {
  stopWriting();
  if (finished_) return;
  for (const std::string& path : written_) {
    std::error_code ec;
    fs::remove(path, ec); // best effort: the run's own error is the message
  }
}

std::string InjectionWriter::fileOfThisRun(const std::string& name) {
  std::string path = (fs::path(outDir_) / name).string();
  std::lock_guard<std::mutex> lock(queueMutex_); // (the second thread adds the pieces it merges)
  written_.push_back(path);
  return path;
}

void InjectionWriter::ctFrame(double time, const std::string& ctName, const std::string& particlesName,
                              const imaging::ImageType* now) {
  const auto t0 = std::chrono::steady_clock::now();
  imaging::ImageType::Pointer made;
  if (!now) made = simulatedCt_();
  const imaging::ImageType& frame = now ? *now : *made;
  imaging::writeVolume(&frame, (fs::path(outDir_) / ctName).string());
  {
    std::lock_guard<std::mutex> lock(queueMutex_);
    written_.push_back((fs::path(outDir_) / ctName).string());
  }
  ctSnapshotWallS_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ctFrames_.push_back({{"index", ctFrames_.size()}, {"time_s", time}, {"simulated_ct", ctName},
                       {"particles", particlesName.empty() ? json(nullptr) : json(particlesName)}});
  // After the cost above is taken: what the observer does (an X-ray projection) is not the frames' cost.
  if (onCtFrame_) onCtFrame_(time, frame);
}

void InjectionWriter::queueParticles(vtkSmartPointer<vtkPolyData> particles, std::string path, std::string union_) {
  if (!particles) throw std::runtime_error(path + ": nothing to write");
  std::unique_lock<std::mutex> lock(queueMutex_);
  if (writeError_) std::rethrow_exception(writeError_);
  if (!writerThread_.joinable()) writerThread_ = std::thread([this] { writeQueued(); });
  queueChanged_.wait(lock, [this] { return queue_.size() < kQueuedSnapshots || writeError_; });
  if (writeError_) std::rethrow_exception(writeError_);
  written_.push_back(path); // removed by the destructor if the run fails, written or not
  if (!union_.empty()) written_.push_back(union_);
  queue_.push_back({std::move(particles), std::move(path), std::move(union_)});
  queueChanged_.notify_all();
}

void InjectionWriter::writeQueued() {
  std::unique_lock<std::mutex> lock(queueMutex_);
  while (true) {
    queueChanged_.wait(lock, [this] { return stopWriter_ || !queue_.empty(); });
    if (stopWriter_) return;
    QueuedPolyData job = std::move(queue_.front());
    queue_.pop_front();
    writingOne_ = true;
    lock.unlock();
    std::exception_ptr error;
    try {
      // Raw and uncompressed (PolyDataIO.h): VTK's writer with LZ4 cost ~3x the file system's own time per
      // byte to save a tenth of the bytes of single-precision fields (issue 23).
      if (job.union_.empty()) imaging::writePolyDataUncompressed(job.data, job.path);
      else writePiece(std::move(job.data), job.path, job.union_);
    } catch (...) {
      error = std::current_exception();
    }
    job.data = nullptr; // freed on this thread, outside the lock
    lock.lock();
    writingOne_ = false;
    if (error && !writeError_) writeError_ = error;
    if (writeError_) queue_.clear();
    queueChanged_.notify_all();
  }
}

void InjectionWriter::writePiece(vtkSmartPointer<vtkPolyData> piece, const std::string& path, const std::string& union_) {
  imaging::writePolyDataUncompressed(piece, path);
  const std::size_t index = pieces_.empty() ? 0 : pieces_.back().first + pieces_.back().snapshots;
  pieces_.push_back({std::move(piece), fs::path(path).filename().string(), index, 1});
  // The carries: the kMergedPieces newest pieces, of equal runs of snapshots, become one (vtkAppendPolyData:
  // points, cells and point arrays in order, the oldest first).
  auto carry = [this] {
    if (pieces_.size() < kMergedPieces) return false;
    for (std::size_t i = pieces_.size() - kMergedPieces; i + 1 < pieces_.size(); ++i)
      if (pieces_[i].snapshots != pieces_.back().snapshots) return false;
    return true;
  };
  while (carry()) {
    const std::size_t from = pieces_.size() - kMergedPieces;
    auto append = vtkSmartPointer<vtkAppendPolyData>::New();
    for (std::size_t i = from; i < pieces_.size(); ++i) append->AddInputData(pieces_[i].data);
    append->Update();
    Piece& merged = pieces_[from];
    merged.data = append->GetOutput();
    merged.snapshots *= kMergedPieces;
    pieces_.resize(from + 1);
    char name[64];
    std::snprintf(name, sizeof name, "particles_piece_%04zu-%04zu.vtp", merged.first, merged.first + merged.snapshots - 1);
    merged.name = name;
    const std::string mergedPath = (fs::path(outDir_) / name).string();
    {
      std::lock_guard<std::mutex> lock(queueMutex_);
      written_.push_back(mergedPath); // (the destructor reads it after this thread has ended)
    }
    imaging::writePolyDataUncompressed(merged.data, mergedPath);
  }
  std::vector<std::string> names;
  for (const Piece& p : pieces_) names.push_back(p.name);
  imaging::writePolyDataPieces(union_, pieces_.back().data, names);
}

void InjectionWriter::waitForQueuedWrites() {
  std::unique_lock<std::mutex> lock(queueMutex_);
  queueChanged_.wait(lock, [this] { return (queue_.empty() && !writingOne_) || writeError_; });
  if (writeError_) std::rethrow_exception(writeError_);
}

void InjectionWriter::stopWriting() noexcept {
  {
    std::lock_guard<std::mutex> lock(queueMutex_);
    stopWriter_ = true;
    queue_.clear();
  }
  queueChanged_.notify_all();
  if (writerThread_.joinable()) writerThread_.join();
}

void InjectionWriter::snapshot(double time, vtkSmartPointer<vtkPolyData> particles, const imaging::ImageType* ctNow) {
  if (!writing()) return;
  char name[64];
  std::snprintf(name, sizeof name, "particles_%04zu.vtp", snapshots_.size());
  queueParticles(std::move(particles), (fs::path(outDir_) / name).string());
  addSnapshot(time, name, ctNow);
}

void InjectionWriter::addSnapshot(double time, const std::string& name, const imaging::ImageType* ctNow) {
  if (ctSnapshots_) {
    char ctName[64];
    std::snprintf(ctName, sizeof ctName, "simulated_ct_%04zu.nrrd", snapshots_.size());
    ctFrame(time, ctName, name, ctNow);
  }
  snapshots_.emplace_back(time, name);
}

void InjectionWriter::snapshotPiece(double time, vtkSmartPointer<vtkPolyData> arrived, const imaging::ImageType* ctNow) {
  if (!writing()) return;
  if (!arrived) throw std::logic_error("inject: a snapshot piece without data");
  char pieceName[64], name[64];
  std::snprintf(pieceName, sizeof pieceName, "particles_piece_%04zu.vtp", snapshots_.size());
  std::snprintf(name, sizeof name, "particles_%04zu.pvtp", snapshots_.size());
  // Both written on the second thread (writePiece); the series (particles.pvd) names the union only once
  // every queued one is on disk (finish).
  queueParticles(std::move(arrived), (fs::path(outDir_) / pieceName).string(), (fs::path(outDir_) / name).string());
  addSnapshot(time, name, ctNow);
}

void InjectionWriter::finish(double time, vtkPolyData* particles, const imaging::ImageType* simulatedCt,
                             const imaging::ImageType* simulatedCtFile, const std::vector<TipRecord>& tipSeries,
                             std::optional<double> baselinePa, json& metrics,
                             const std::vector<std::pair<std::string, std::string>>& textFiles) {
  if (!writing()) return;
  snapshot(time, particles, simulatedCt);
  waitForQueuedWrites(); // the series is whole before particles.pvd names it
  stopWriting();
  imaging::writeTextAtomically(fileOfThisRun("particles.pvd"), particleCollection(snapshots_));
  imaging::writeTextAtomically(fileOfThisRun("tip_pressure.csv"), tipPressureCsv(tipSeries, baselinePa));
  imaging::writeVolume(simulatedCtFile, fileOfThisRun("simulated_ct.nrrd"));
  imaging::writeTextAtomically(fileOfThisRun("scene.json"), toJson(scene_).dump(2) + "\n");
  metrics["snapshots"] = snapshots_.size();
  if (ctSnapshots_) {
    metrics["simulated_ct_snapshots"] = ctFrames_.size();
    metrics["simulated_ct_snapshots_wall_s"] = ctSnapshotWallS_; // making and writing them
    const json sequence{{"frames", ctFrames_},
                        {"final_simulated_ct", "simulated_ct.nrrd"},
                        {"simulated_ct_hu_per_relative_density", huPerRelativeDensity_},
                        {"note", "frame 0 (t = 0 s, no cement) is the background of an X-ray sequence; the frames "
                                 "cover the region of interest; the last frame is the final state, which "
                                 "simulated_ct.nrrd holds on the input CT's grid"}};
    imaging::writeTextAtomically(fileOfThisRun("sequence.json"), sequence.dump(2) + "\n");
  }
  for (const auto& [name, text] : textFiles) imaging::writeTextAtomically(fileOfThisRun(name), text);
  imaging::writeTextAtomically(fileOfThisRun("metrics.json"), metrics.dump(2) + "\n");
  finished_ = true;
}

InjectionProgress::InjectionProgress(const InjectionRunOptions& options, std::chrono::steady_clock::time_point start,
                                     double durationS)
    : options_(options), start_(start), duration_(durationS), tty_(options.progress && isatty(STDERR_FILENO)) {}

double InjectionProgress::wallSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool InjectionProgress::step(double t, const std::function<std::string()>& state) {
  auto number = [](double x, int precision) {
    std::ostringstream s;
    s << std::setprecision(precision) << x;
    return s.str();
  };
  const double wall = wallSeconds();
  const double fraction = std::min(1.0, t / duration_);
  if (options_.progress && wall >= nextReport_) {
    std::ostringstream line;
    line << "inject: t " << number(t, 4) << " / " << number(duration_, 4) << " s, " << state();
    if (tty_ && fraction > 0) line << ", ETA " << number(wall * (1 - fraction) / fraction, 3) << " s";
    if (tty_) std::cerr << "\r" << line.str() << "\033[K" << std::flush;
    else std::cerr << line.str() << "\n";
    nextReport_ = wall + (tty_ ? 1.0 : 30.0);
  }
  if (options_.onProgress && fraction >= nextFraction_) {
    nextFraction_ = fraction + 0.01;
    if (!options_.onProgress(fraction)) return false;
  }
  return true;
}

void InjectionProgress::done() const {
  if (tty_) std::cerr << "\n";
}

} // namespace cementsph::scene::detail
