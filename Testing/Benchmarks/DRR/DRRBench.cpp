// drr-bench: the issue-5 DRR speed and agreement figures on this machine.
// A 256x256x200 CT phantom (0.9 x 0.9 x 1.0 mm voxels: an elliptical soft-tissue body at 40 HU around
// a trabecular bone block with a 3000 HU cement ball) is projected onto a 512x512 detector
// (400 x 400 mm, sad 1000, sid 1500) by
//   1. vtkDRRFilter in process, 1 and 2 threads (HU -> mu conversion included, file reading not);
//   2. the `cementsph drr` program (read .mha, DRR, write .nrrd + .png), 1 and 2 threads;
//   3. `plastimatch drr -i exact` on the same .mha with the same geometry, OMP_NUM_THREADS 1 and 2
//      (when plastimatch is on PATH), whose image is compared with ours pixel by pixel.
// DRR-only times are the best of N runs (default 3), whole programs the median of the N.
// Usage: drr-bench [work-dir] [--repeats=N]. Prints Markdown.
#include "SyntheticVolumes.h"
#include "cementsph/drr/vtkDRRFilter.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkImageData.h>
#include <vtkNew.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/resource.h>

namespace fs = std::filesystem;
using namespace cementsph;
using namespace cementsph::testing;

namespace {

constexpr double kPi = 3.14159265358979323846;

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Setup {
  int rows = 512, cols = 512;
  double heightMm = 400, widthMm = 400, sad = 1000, sid = 1500;
  double gantryDeg = 0.0;
  Vec3 iso{0, 0, 0};
};

ImageType::Pointer makePhantom() {
  Grid grid;
  grid.size = {256, 256, 200};
  grid.spacing = {0.9, 0.9, 1.0};
  for (int a = 0; a < 3; ++a) grid.origin[a] = -0.5 * (grid.size[a] - 1) * grid.spacing[a];
  const BonePhantom bone({0, 10, 0}, {30, 25, 45}, 7, 80);
  auto image = makeImage(grid, -1000.0f);
  float* out = image->GetBufferPointer();
  const auto& s = grid.size;
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(s[2]); ++k)
    for (unsigned j = 0; j < s[1]; ++j)
      for (unsigned i = 0; i < s[0]; ++i) {
        const Vec3 p{grid.origin[0] + i * grid.spacing[0], grid.origin[1] + j * grid.spacing[1],
                     grid.origin[2] + k * grid.spacing[2]};
        double hu = -1000.0;
        const double body = (p[0] / 105.0) * (p[0] / 105.0) + (p[1] / 85.0) * (p[1] / 85.0);
        if (body <= 1.0) hu = 40.0;
        const double b = bone.valueAt(p);
        if (b > -990.0) hu = b;
        const double c2 = p[0] * p[0] + (p[1] - 12.0) * (p[1] - 12.0) + (p[2] - 5.0) * (p[2] - 5.0);
        if (c2 <= 64.0) hu = 3000.0;
        out[(static_cast<std::size_t>(k) * s[1] + j) * s[0] + i] = static_cast<float>(hu);
      }
  return image;
}

struct Image2D {
  int cols = 0, rows = 0;
  std::vector<float> v; // row j = 0 at the bottom (our convention)
};

Image2D runFilter(vtkImageData* hu, const Setup& s, int threads, double& seconds) {
  vtkNew<vtkDRRFilter> f;
  f->SetInputData(hu);
  f->SetDetectorRows(s.rows);
  f->SetDetectorColumns(s.cols);
  f->SetDetectorHeight(s.heightMm);
  f->SetDetectorWidth(s.widthMm);
  f->SetSourceAxisDistance(s.sad);
  f->SetSourceImageDistance(s.sid);
  f->SetGantryAngle(s.gantryDeg);
  f->SetIsocenter(s.iso[0], s.iso[1], s.iso[2]);
  f->SetNumberOfThreads(threads);
  const double t = now();
  f->Update();
  seconds = now() - t;
  Image2D d;
  d.cols = s.cols;
  d.rows = s.rows;
  const float* p = static_cast<const float*>(f->GetOutput()->GetScalarPointer());
  d.v.assign(p, p + static_cast<std::size_t>(s.cols) * s.rows);
  return d;
}

// plastimatch writes PFM rows top first (not the PFM convention); flipped into ours.
bool readPfm(const fs::path& path, Image2D& d) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  double scale;
  if (!(in >> magic >> d.cols >> d.rows >> scale) || magic != "Pf") return false;
  in.get();
  std::vector<float> top(static_cast<std::size_t>(d.cols) * d.rows);
  if (!in.read(reinterpret_cast<char*>(top.data()), static_cast<std::streamsize>(top.size() * sizeof(float))))
    return false;
  d.v.resize(top.size());
  for (int r = 0; r < d.rows; ++r)
    std::copy_n(&top[static_cast<std::size_t>(r) * d.cols], d.cols,
                &d.v[static_cast<std::size_t>(d.rows - 1 - r) * d.cols]);
  return true;
}

// Best wall time of repeats runs; reported (optional) gets the smallest "Total time: X secs" the
// program printed (plastimatch's own figure for its DRR, without process start-up).
// cpu (optional) gets the CPU time (user + system, all threads) of the last run: on a shared machine
// it does not grow with the load the way wall time does.
double childCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_CHILDREN, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

double timeCommand(const std::string& cmd, int repeats, const fs::path& log, double* reported = nullptr,
                   double* cpu = nullptr) {
  double best = 1e30;
  if (reported) *reported = 1e30;
  for (int r = 0; r < repeats; ++r) {
    const double t = now();
    const double cpu0 = childCpuSeconds();
    const int status = std::system((cmd + " > " + log.string() + " 2>&1").c_str());
    const double dt = now() - t;
    if (cpu) *cpu = childCpuSeconds() - cpu0;
    if (status != 0) {
      std::cerr << "drr-bench: failed (see " << log << "): " << cmd << "\n";
      return -1.0;
    }
    best = std::min(best, dt);
    std::ifstream in(log);
    std::string line;
    while (reported && std::getline(in, line))
      if (line.rfind("Total time:", 0) == 0) *reported = std::min(*reported, std::atof(line.c_str() + 11));
  }
  return best;
}

// The median of a set of run times (the whole-program figures: a shared machine's outliers do not count).
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fmt(double v, const char* f = "%.3f") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

} // namespace

int main(int argc, char** argv) {
  fs::path work = fs::current_path() / "drr-bench";
  int repeats = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--repeats=", 0) == 0) repeats = std::max(1, std::atoi(a.c_str() + 10));
    else work = a;
  }
  fs::create_directories(work);
  const fs::path volumePath = work / "phantom.mha";

  double t = now();
  const ImageType::Pointer ct = makePhantom();
  imaging::writeVolume(ct, volumePath.string());
  auto hu = imaging::toVtk(ct.GetPointer());
  std::fprintf(stderr, "phantom made and written in %.1f s\n", now() - t);

  std::cout << "## DRR: 512x512 detector, 256x256x200 volume\n\n";
  std::cout << "Phantom: 256x256x200 voxels of 0.9x0.9x1.0 mm (soft-tissue body, bone block, cement ball); "
               "detector 512x512 px, 400x400 mm; sad 1000 mm, sid 1500 mm; DRR alone: best of, whole programs: median of "
            << repeats << " runs.\n\n";

  const bool havePlastimatch = std::system("command -v plastimatch > /dev/null 2>&1") == 0;
  std::string version;
  if (havePlastimatch) {
    std::system(("plastimatch --version > " + (work / "version.txt").string() + " 2>&1").c_str());
    std::ifstream v(work / "version.txt");
    std::getline(v, version);
  }

  for (double gantry : {0.0, 30.0}) {
    Setup s;
    s.gantryDeg = gantry;
    std::cout << "### Gantry " << gantry << " deg\n\n";
    std::cout << "| implementation | threads | DRR time, best (s) | whole program, median (s) |\n|---|---|---|---|\n";
    // The four contenders run in turn within each repeat (not one after the other for all repeats),
    // so that load from other users of a shared machine hits them alike.
    Image2D ours;
    double drrBest[3] = {0, 1e30, 1e30}, plmReported[3] = {0, 1e30, 1e30};
    std::vector<double> wholeRuns[3], plmRuns[3], wholeCpu[3], plmCpu[3];
    auto oursCommand = [&](int threads) {
      std::ostringstream cmd;
      cmd << CEMENTSPH_EXE << " drr --volume " << volumePath << " --out " << (work / "ours") << " --threads "
          << threads << " --detector-pixels " << s.rows << "," << s.cols << " --detector-size-mm " << s.heightMm
          << "," << s.widthMm << " --sad-mm " << s.sad << " --sid-mm " << s.sid << " --isocenter-mm 0,0,0"
          << " --gantry-angle-deg " << s.gantryDeg;
      return cmd.str();
    };
    auto plastimatchCommand = [&](int threads) {
      // Debian 12's plastimatch 1.9.4 reads --gantry-angle in radians (its help says degrees), and
      // takes -r / -z with the horizontal (column) figure first; see docs/drr-figures.md.
      std::ostringstream cmd;
      cmd << "OMP_NUM_THREADS=" << threads << " plastimatch drr -i exact -t pfm"
          << " -r \"" << s.cols << " " << s.rows << "\" -z \"" << s.widthMm << " " << s.heightMm << "\""
          << " --sad " << s.sad << " --sid " << s.sid << " -o \"0 0 0\" -y " << fmt(s.gantryDeg * kPi / 180.0, "%.12g")
          << " -O " << (work / "plm").string() << " " << volumePath;
      return cmd.str();
    };
    for (int r = 0; r < repeats; ++r) {
      for (int threads : {1, 2}) {
        double dt;
        ours = runFilter(hu, s, threads, dt);
        drrBest[threads] = std::min(drrBest[threads], dt);
        double cpu = 0.0;
        wholeRuns[threads].push_back(timeCommand(oursCommand(threads), 1, work / "ours.log", nullptr, &cpu));
        wholeCpu[threads].push_back(cpu);
        if (havePlastimatch) {
          double reported;
          plmRuns[threads].push_back(
              timeCommand(plastimatchCommand(threads), 1, work / "plastimatch.log", &reported, &cpu));
          plmCpu[threads].push_back(cpu);
          plmReported[threads] = std::min(plmReported[threads], reported);
        }
      }
    }
    const double whole[3] = {0, median(wholeRuns[1]), median(wholeRuns[2])};
    const double plm[3] = {0, median(plmRuns[1]), median(plmRuns[2])};
    for (int threads : {1, 2})
      std::cout << "| vtkDRRFilter / cementsph drr | " << threads << " | " << fmt(drrBest[threads]) << " | "
                << fmt(whole[threads]) << " |\n";
    if (!havePlastimatch) {
      std::cout << "\nplastimatch not found on PATH: no comparison.\n\n";
      continue;
    }
    for (int threads : {1, 2})
      std::cout << "| plastimatch drr -i exact (" << version << ") | " << threads << " | "
                << fmt(plmReported[threads]) << " (its \"Total time\") | " << fmt(plm[threads]) << " |\n";
    const double best1 = drrBest[1], best2 = drrBest[2];
    Image2D ref;
    if (!readPfm(work / "plm0000.pfm", ref) || ref.cols != ours.cols || ref.rows != ours.rows) {
      std::cout << "\nplastimatch's image could not be read or has another size.\n\n";
      continue;
    }
    double maxRef = 0, sumAbs = 0, sumSq = 0, maxAbs = 0, sumRef = 0, sumOurs = 0;
    std::size_t over1 = 0;
    for (std::size_t k = 0; k < ref.v.size(); ++k) maxRef = std::max(maxRef, static_cast<double>(ref.v[k]));
    for (std::size_t k = 0; k < ref.v.size(); ++k) {
      const double d = std::abs(static_cast<double>(ours.v[k]) - ref.v[k]);
      sumAbs += d;
      sumSq += d * d;
      maxAbs = std::max(maxAbs, d);
      sumRef += ref.v[k];
      sumOurs += ours.v[k];
      over1 += d > 0.01 * maxRef;
    }
    const double n = static_cast<double>(ref.v.size());
    std::cout << "\nPixel difference, ours - plastimatch, normalised by plastimatch's maximum (" << fmt(maxRef, "%.4f")
              << "): mean |d| " << fmt(100 * sumAbs / n / maxRef, "%.2e") << " %, RMS "
              << fmt(100 * std::sqrt(sumSq / n) / maxRef, "%.2e") << " %, max |d| "
              << fmt(100 * maxAbs / maxRef, "%.2e") << " %; pixels off by more than 1 %: " << over1
              << "; image sums differ by " << fmt(100 * std::abs(sumOurs - sumRef) / std::max(sumRef, 1e-30), "%.2e")
              << " %.\n";
    std::cout << "Speed-up, DRR time (ours: vtkDRRFilter::Update including HU -> mu; plastimatch: its "
                 "reported total): 1 thread "
              << fmt(plmReported[1] / best1, "%.1f") << "x, 2 threads " << fmt(plmReported[2] / best2, "%.1f")
              << "x.\n";
    std::cout << "Speed-up, whole program (read .mha, DRR, write; process start-up included): 1 thread "
              << fmt(plm[1] / whole[1], "%.2f") << "x, 2 threads " << fmt(plm[2] / whole[2], "%.2f") << "x (medians of wall "
                 "time); CPU time (user + system, median): ours "
              << fmt(median(wholeCpu[1])) << " / " << fmt(median(wholeCpu[2])) << " s, plastimatch "
              << fmt(median(plmCpu[1])) << " / " << fmt(median(plmCpu[2])) << " s at 1 / 2 threads: "
              << fmt(median(plmCpu[1]) / median(wholeCpu[1]), "%.2f") << "x / "
              << fmt(median(plmCpu[2]) / median(wholeCpu[2]), "%.2f") << "x.\n\n";
  }
  // Fixed cost of every cementsph run: loading ~150 VTK/ITK shared libraries.
  const double startup = timeCommand(std::string(CEMENTSPH_EXE) + " --version", repeats, work / "version.log");
  const double plmStartup = havePlastimatch ? timeCommand("plastimatch --version", repeats, work / "version.log") : 0.0;
  std::cout << "Process start-up alone (`--version`): cementsph " << fmt(startup) << " s, plastimatch "
            << fmt(plmStartup) << " s.\n";
  return 0;
}
