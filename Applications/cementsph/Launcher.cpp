// `cementsph`: the program users type. It runs the program that holds the subcommand in its own place
// (execv: same process id, arguments, streams and exit status), from libexec/cementsph next to it:
//   cementsph drr ...   -> cementsph-drr: only the DRR command, linked against ITK's IO and VTK's common
//                          and image libraries (about a third of the libraries; the dynamic loader's symbol
//                          lookups over ~165 VTK/ITK/GL libraries were a quarter of a whole DRR run);
//   anything else       -> cementsph-all: every subcommand, --help and --version.
// Itself it links only the C library, so the hand-over costs about a millisecond.
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <unistd.h>

int main(int argc, char** argv) {
  char self[PATH_MAX];
  const ssize_t length = readlink("/proc/self/exe", self, sizeof self - 1);
  if (length <= 0) {
    std::fprintf(stderr, "cementsph: cannot find its own location (/proc/self/exe: %s)\n", std::strerror(errno));
    return 2;
  }
  self[length] = '\0';
  std::string folder(self);
  folder.erase(folder.rfind('/'));
  const bool drr = argc > 1 && std::strcmp(argv[1], "drr") == 0;
  const std::string program = folder + "/../libexec/cementsph/" + (drr ? "cementsph-drr" : "cementsph-all");
  // OpenMP threads wait passively (sleep at a barrier) unless the user says otherwise: with spinning waits, a
  // thread whose core another program holds stalls the whole team, and `--threads 2` on a busy 2-core machine
  // ran 5-10x slower than one thread (BENCHMARKS.md, "Threads"). Set before the program starts: libgomp
  // reads it once, when it loads.
  setenv("OMP_WAIT_POLICY", "PASSIVE", 0);
  execv(program.c_str(), argv);
  std::fprintf(stderr, "cementsph: cannot run %s: %s; rebuild, or reinstall with cmake --install\n",
               program.c_str(), std::strerror(errno));
  return 2;
}
