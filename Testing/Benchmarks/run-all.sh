#!/usr/bin/env bash
# Every figure BENCHMARKS.md quotes, from one script (issue 23, item 5). Not a test and not part of the
# README's test command: it takes minutes and its figures depend on the machine and its load.
#
# Usage:  Testing/Benchmarks/run-all.sh [OUT_DIR]
#   QUICK=1        a subset in under ~3 minutes (1 and 5 ml, one repetition, the whole-scan case at 1 ml,
#                  threads at 5 ml, the SPH step benchmark's 205k-particle box only; no DRR/registration)
#   BUILD=DIR      the build to measure (default: build); its bin/cementsph, bin/SPHStepBenchmark,
#                  bin/drr-bench and bin/imaging-bench are used where they exist
#   BASELINE=DIR   a prefix holding bin/cementsph (and libexec/cementsph/) of the code to compare against,
#                  run in the same session, interleaved with the measured build. Without it the voxel
#                  figures have no "before" column. See BENCHMARKS.md for how the quoted baseline was made.
#   REPEATS=N      repetitions of each voxel run (default 3; QUICK: 1); medians are quoted
#   KEEP_RUNS=1    keep each run's output folder under OUT_DIR/runs (default: all removed when the script ends)
#   IMAGING_ARGS   arguments for imaging-bench (default: --only=registration)
#   ONLY=LIST      only these sections, a comma list of voxel (the bundled phantom's volumes), region (the
#                  whole-scan region against the 40 mm one), threads, snapshots (5 ml with its 100 snapshots
#                  against one), particles (every engine and the paper preset against voxel-darcy, 0.5 and 1 ml; PARTICLE_VOLUMES=0.5,1,5
#                  for 5 ml itself), sph, plan (an oblique plan against the axial one), peers (DRR, registration);
#                  default all. The tables then hold only those sections' figures
#
# Writes OUT_DIR/benchmarks.md (the dated tables, machine and load average) and OUT_DIR/runs.jsonl (every
# run: wall and CPU time, peak memory, solver statistics) and prints the Markdown.
# Needs: python3 (no modules beyond the standard library), /usr/bin/env, lscpu.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
case "$BUILD" in /*) ;; *) BUILD=$ROOT/$BUILD ;; esac
OUT=${1:-/tmp/cementsph-bench-$(date -u +%Y%m%dT%H%M%SZ)}
mkdir -p "$OUT"
export ROOT BUILD OUT
export QUICK=${QUICK:-0} BASELINE=${BASELINE:-} REPEATS=${REPEATS:-} KEEP_RUNS=${KEEP_RUNS:-0} IMAGING_ARGS=${IMAGING_ARGS:---only=registration} ONLY=${ONLY:-}
exec python3 - "$@" <<'PYTHON'
import atexit, datetime, json, math, os, re, shutil, statistics, subprocess, sys, time

ROOT, BUILD, OUT = os.environ["ROOT"], os.environ["BUILD"], os.environ["OUT"]
QUICK = os.environ.get("QUICK", "0") not in ("", "0")
BASELINE = os.environ.get("BASELINE", "")
REPEATS = int(os.environ.get("REPEATS") or (1 if QUICK else 3))
KEEP_RUNS = os.environ.get("KEEP_RUNS", "0") not in ("", "0")
finished_runs = []  # the run folders to delete at the end (inject())
atexit.register(lambda: [shutil.rmtree(d, ignore_errors=True) for d in finished_runs])
started = datetime.datetime.now(datetime.timezone.utc)
loads = []
os.makedirs(os.path.join(OUT, "runs"), exist_ok=True)
runs_log = open(os.path.join(OUT, "runs.jsonl"), "w")


def load():
    with open("/proc/loadavg") as f:
        v = [float(x) for x in f.read().split()[:3]]
    loads.append(v[0])
    return v


def run(cmd, env=None, log=None, cwd=None):
    """Runs cmd; returns wall and CPU seconds (user + system) and peak memory of that one process tree's
    largest process (wait4's rusage)."""
    e = dict(os.environ)
    for k, v in (env or {}).items():
        if v is None:
            e.pop(k, None)  # unset: the OpenMP runtime's default
        else:
            e[k] = v
    load()
    t0 = time.monotonic()
    with open(log or os.devnull, "w") as out:
        p = subprocess.Popen(cmd, env=e, stdout=out, stderr=subprocess.STDOUT, cwd=cwd)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    load()
    rc = os.waitstatus_to_exitcode(status)
    return {"rc": rc, "wall": wall, "cpu": ru.ru_utime + ru.ru_stime, "rss_mb": ru.ru_maxrss / 1024.0}


def exe(prefix, name):
    p = os.path.join(prefix, "bin", name)
    return p if os.path.exists(p) else None


CURRENT = exe(BUILD, "cementsph")
if not CURRENT:
    sys.exit("run-all.sh: no %s/bin/cementsph: build the target cementsph first" % BUILD)
BASE = exe(BASELINE, "cementsph") if BASELINE else None
CT = os.path.join(ROOT, "Data/foam-phantom/pre.nrrd")
SCENE = os.path.join(ROOT, "Data/scenes/paper.json")
TIP = "22.325,21.855,21.75"  # README's tip on the bundled phantom


def inject(binary, tag, volume, threads=1, env=None, ct=CT, tip=TIP, extra=()):
    out = os.path.join(OUT, "runs", tag)
    cmd = [binary, "inject", "--ct", ct, "--scene", SCENE, "--tip-mm", tip, "--volume-ml", str(volume),
           "--no-pictures", "--quiet", "--threads", str(threads), "--out", out] + list(extra)
    r = run(cmd, env=env, log=out + ".log")
    r.update(tag=tag, volume_ml=volume, threads=threads, env=env or {}, cmd=" ".join(cmd[1:]).replace(ROOT + "/", ""))
    if r["rc"] == 0:
        with open(os.path.join(out, "metrics.json")) as f:
            m = json.load(f)
        r.update(loop_s=m.get("wall_time_s"), steps=m.get("pressure_solves"), iterations=m.get("pressure_solver_iterations_mean"),
                 solve_s=m.get("pressure_solve_wall_s"), assembly_s=m.get("pressure_assembly_wall_s"),
                 tip_pa=m.get("final_tip_pressure_pa"), cement_voxels=m.get("cement_voxels"),
                 spread_mm=m.get("mean_spreading_distance_mm"), step_count=m.get("steps", m.get("pressure_solves")),
                 points=m.get("cement_points"),
                 mb=sum(os.path.getsize(os.path.join(out, f)) for f in os.listdir(out)) / 1e6)  # the files the run wrote
    # The run's files go when the script ends (a full run of this script wrote ~8 GB of snapshots, and several
    # runs' kept files filled a disk); KEEP_RUNS=1 keeps them. Not as each run is read: on a journal-less ext4 (this
    # machine's) a file created within a minute or more of many deletions is slow to make (the inode allocator skips
    # recently deleted inodes one by one: ext4_create, recently_deleted), which charged 0.1-0.2 s of kernel time to
    # the next run's 239 snapshot files and none to a run without snapshots (session 11).
    if not KEEP_RUNS:
        finished_runs.append(out)
    runs_log.write(json.dumps(r) + "\n")
    runs_log.flush()
    print("  %-28s %6.2f s wall %6.2f s CPU %7.0f MB  load %.2f" % (tag, r["wall"], r["cpu"], r["rss_mb"], loads[-1]),
          file=sys.stderr)
    return r


def medianOf(v):
    return statistics.median(v) if v else float("nan")


def med(rs, key):
    return medianOf([r[key] for r in rs if r.get("rc") == 0 and r.get(key) is not None])


def interleaved(cases, tag):
    """REPEATS rounds over every case and both builds, the cases' order and the builds' alternating from round to
    round, so that a drift of the machine's speed over the minutes (~30 % within a run on the 2-core machine) falls
    on every case alike. cases: {key: (volume in ml, inject()'s keyword arguments)}; tag(key): the runs' name."""
    res = {key: {"current": [], "baseline": []} for key in cases}
    for rep in range(REPEATS):
        order = [("baseline", BASE), ("current", CURRENT)] if rep % 2 == 0 else [("current", CURRENT), ("baseline", BASE)]
        for key in (list(cases) if rep % 2 == 0 else list(cases)[::-1]):
            volume, kw = cases[key]
            for variant, binary in order:
                if binary:
                    res[key][variant].append(inject(binary, "%s-%s-%d" % (tag(key), variant, rep), volume, **kw))
    return res


def roundRatios(a, b, key):
    """a's key over b's, round by round (interleaved(): the two runs of a round are a minute apart)."""
    return [x[key] / y[key] for x, y in zip(a, b) if x.get("rc") == 0 and y.get("rc") == 0 and x.get(key) and y.get(key)]


def demote(text):
    """A peer benchmark's own Markdown, its headings two levels down (under this file's ###)."""
    return re.sub(r"(?m)^(#+) ", lambda m: "#" * min(len(m.group(1)) + 2, 6) + " ", text)


def fmt(x, f="%.2f"):
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f % x


def ratio(a, b, f="%.2f"):
    return "n/a" if not a or not b or math.isnan(a) or math.isnan(b) else f % (a / b)


ONLY = [x.strip() for x in os.environ.get("ONLY", "").split(",") if x.strip()]
SECTIONS = ("voxel", "region", "threads", "snapshots", "particles", "sph", "plan", "peers")
for x in ONLY:
    if x not in SECTIONS:
        sys.exit("run-all.sh: ONLY=%s: unknown section %r; use a comma list of %s" % (os.environ["ONLY"], x, ", ".join(SECTIONS)))


def want(section):
    return not ONLY or section in ONLY


summary = []  # (benchmark, figure, ratio, command)
details = []
print("run-all.sh: %s, output %s" % ("QUICK" if QUICK else "full", OUT), file=sys.stderr)
start_load = load()

if want("voxel"):
    # 1. The voxel injection on the bundled phantom (the paper's scene, 1 thread), against the baseline.
    volumes = [1, 5] if QUICK else [1, 5, 10]
    # The growth ratios are taken round by round (interleaved()), their median quoted.
    phantom = interleaved({v: (v, {}) for v in volumes}, lambda v: "phantom-%gml" % v)
    rows = ["| volume | build | wall (s) | CPU (s) | peak memory (MB) | solves | CG iterations, mean | solve (s) | tip pressure (Pa) |",
            "|---|---|---|---|---|---|---|---|---|"]
    for v in volumes:
        for variant in ("baseline", "current"):
            rs = phantom[v][variant]
            if not rs:
                continue
            rows.append("| %g ml | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                v, variant, fmt(med(rs, "wall")), fmt(med(rs, "cpu")), fmt(med(rs, "rss_mb"), "%.0f"),
                fmt(med(rs, "steps"), "%.0f"), fmt(med(rs, "iterations"), "%.1f"), fmt(med(rs, "solve_s")),
                fmt(med(rs, "tip_pa"), "%.1f")))
        cur, base = phantom[v]["current"], phantom[v]["baseline"]
        cmd = "cementsph " + cur[0]["cmd"].split(" --out ")[0]
        summary.append(("voxel inject %g ml, phantom, 1 thread" % v, "%s s CPU (%s s wall)" % (fmt(med(cur, "cpu")), fmt(med(cur, "wall"))),
                        "%s x faster (CPU), %s x (wall)" % (ratio(med(base, "cpu"), med(cur, "cpu")), ratio(med(base, "wall"), med(cur, "wall"))) if base else "n/a", cmd))
        summary.append(("  its pressure solve", "%s s, %s CG iterations/solve" % (fmt(med(cur, "solve_s")), fmt(med(cur, "iterations"), "%.1f")),
                        "%s x faster, %s x fewer iterations" % (ratio(med(base, "solve_s"), med(cur, "solve_s")), ratio(med(base, "iterations"), med(cur, "iterations"), "%.1f")) if base else "n/a", "(metrics.json)"))
    growth = ["| build | CPU 5 ml / 1 ml | exponent 1-5 ml | CPU 10 ml / 5 ml (median of the rounds' ratios) | exponent 5-10 ml |", "|---|---|---|---|---|"]
    for variant in ("baseline", "current"):
        c = {v: med(phantom[v][variant], "cpu") for v in volumes if phantom[v][variant]}
        if 1 not in c or 5 not in c:
            continue
        e15 = math.log(c[5] / c[1]) / math.log(5)
        rounds = roundRatios(phantom[10][variant], phantom[5][variant], "cpu") if 10 in c else []
        r510 = medianOf(rounds)
        e510 = math.log(r510) / math.log(2) if 10 in c else float("nan")
        growth.append("| %s | %.2f | %.2f | %s | %s |" % (variant, c[5] / c[1], e15, fmt(r510), fmt(e510)))
        if variant == "current":
            summary.append(("voxel inject cost growth with volume", "CPU ~ V^%.2f (1-5 ml)%s" % (e15, ", V^%.2f (5-10 ml): 10 ml = %.2f x 5 ml (median of %d rounds' ratios; %s-%s)" % (
                                e510, r510, len(rounds), fmt(min(rounds)), fmt(max(rounds))) if rounds else ""),
                            "target 10 ml <= 2.5 x 5 ml: %s" % ("met" if r510 <= 2.5 else "not met") if 10 in c else "n/a", "(the runs above)"))
    details.append("### Voxel Darcy injection, bundled phantom (94 x 94 x 88 voxels), paper scene, 1 thread\n\n"
                   "Medians of %d interleaved run(s) per build; CPU = user + system of the process.\n\n%s\n\nCost growth (CPU time):\n\n%s\n"
                   % (REPEATS, "\n".join(rows), "\n".join(growth)))

if want("region"):
    # 2. Whole-scan region against the 40 mm region on a larger foam CT (200 x 200 x 188 voxels).
    big = os.path.join(OUT, "big-phantom")
    if not os.path.exists(os.path.join(big, "pre.nrrd")):
        r = run([CURRENT, "phantom", "--out", big, "--size-mm", "80", "--no-post", "--threads", "1", "--quiet"], log=big + ".log")
        if r["rc"] != 0:
            sys.exit("run-all.sh: could not make the large phantom (see %s.log)" % big)
    bigTip = "47.705,46.295,48.25"  # a pore voxel near the centre of seed 1's 80 mm block
    bigVolume = 1 if QUICK else 5
    # The ratio is taken round by round (interleaved()), its median quoted.
    region = interleaved({roi: (bigVolume, dict(ct=os.path.join(big, "pre.nrrd"), tip=bigTip,
                                                extra=["--set", "roi_size_mm=%d" % roi, "--allow-large"])) for roi in (40, 200)},
                         lambda roi: "region-%dmm" % roi)

    def roundRatio(variant, key):
        return medianOf(roundRatios(region[200][variant], region[40][variant], key))
    # The per-step passes other than the solve (numbering, front, assembly: metrics' pressure_assembly_wall_s)
    # are what a region-sized data structure would slow down; the peak memory is the whole process's.
    # "Outside the loop": the process's wall time less metrics.json's wall_time_s (start-up, reading the CT, writing
    # the results on the whole scan's grid: simulated_ct.nrrd's compression the largest part).
    for roi in (40, 200):
        for variant in ("baseline", "current"):
            for r in region[roi][variant]:
                if r.get("loop_s") is not None:
                    r["outside_s"] = r["wall"] - r["loop_s"]
    rows = ["| region | build | wall (s) | CPU (s) | peak memory (MB) | solve (s) | other per-step passes (s) | outside the injection loop (s) | tip pressure (Pa) |", "|---|---|---|---|---|---|---|---|---|"]
    for roi in (40, 200):
        for variant in ("baseline", "current"):
            rs = region[roi][variant]
            if rs:
                rows.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s |" % ("40 mm" if roi == 40 else "whole scan (200 mm)", variant, fmt(med(rs, "wall")),
                            fmt(med(rs, "cpu")), fmt(med(rs, "rss_mb"), "%.0f"), fmt(med(rs, "solve_s"), "%.3f"),
                            fmt(med(rs, "assembly_s"), "%.3f"), fmt(med(rs, "outside_s"), "%.2f"), fmt(med(rs, "tip_pa"), "%.1f")))
    b40 = region[40]
    summary.append(("voxel inject %g ml, 40 mm region of a 200 x 200 x 188 CT: outside the injection loop" % bigVolume,
                    "%s s of %s s wall" % (fmt(med(b40["current"], "outside_s")), fmt(med(b40["current"], "wall"))),
                    "baseline: %s s of %s s (%s x)" % (fmt(med(b40["baseline"], "outside_s")), fmt(med(b40["baseline"], "wall")),
                                                      ratio(med(b40["baseline"], "outside_s"), med(b40["current"], "outside_s"))) if BASE else "n/a",
                    "(the region rows; metrics.json wall_time_s)"))
    for variant in ("baseline", "current"):
        a, b = region[200][variant], region[40][variant]
        if a and b:
            rows.append("\n%s: whole scan / 40 mm (medians of the rounds' ratios) = %s x CPU, %s x wall, %s x memory, %s x solve time" % (
                variant, fmt(roundRatio(variant, "cpu")), fmt(roundRatio(variant, "wall")),
                fmt(roundRatio(variant, "rss_mb")), fmt(roundRatio(variant, "solve_s"))))
    a, b = region[200]["current"], region[40]["current"]
    summary.append(("voxel inject %g ml, whole-scan region / 40 mm region (200 x 200 x 188 CT)" % bigVolume,
                    "%s x CPU, %s x memory (medians of %d rounds' ratios)" % (fmt(roundRatio("current", "cpu")), fmt(roundRatio("current", "rss_mb")), len(a)),
                    "baseline: %s x CPU, %s x memory" % (fmt(roundRatio("baseline", "cpu")), fmt(roundRatio("baseline", "rss_mb"))) if BASE else "n/a",
                    # the whole-scan run's command, its region setting kept (only the output folder dropped)
                    "cementsph " + re.sub(r" --out \S+", "", a[0]["cmd"])))
    details.append("### Whole-scan region against the 40 mm region (`cementsph phantom --size-mm 80`: 200 x 200 x 188 voxels), %g ml, 1 thread\n\n%s\n"
                   % (bigVolume, "\n".join(rows)))

if want("threads"):
    # 3. Threads: 1 against 2, with passive and with active (spinning) OpenMP waiting, at 5 ml.
    rows = ["| build | threads | OMP_WAIT_POLICY | wall (s) | CPU (s) | wall / 1 thread |", "|---|---|---|---|---|---|"]
    for variant, binary in (("current", CURRENT), ("baseline", BASE)):
        if not binary or (QUICK and variant == "baseline"):
            continue
        one = None
        kinds = ((1, "PASSIVE"), (2, "PASSIVE"), (2, "unset"), (2, "ACTIVE"))
        reps = REPEATS if variant == "current" else 1  # the baseline once: its spinning runs take minutes
        # Interleaved rounds (the order alternating), so that the machine's drift over the minutes falls on every kind alike.
        done = {kind: [] for kind in kinds}
        for rep in range(reps):
            for threads, policy in (kinds if rep % 2 == 0 else tuple(reversed(kinds))):
                done[(threads, policy)].append(inject(binary, "threads-%s-%d-%s-%d" % (variant, threads, policy, rep), 5, threads=threads,
                                                      env={"OMP_WAIT_POLICY": None if policy == "unset" else policy}))
        for threads, policy in kinds:
            rs = done[(threads, policy)]
            w = med(rs, "wall")
            one = one or w
            rows.append("| %s | %d | %s | %s | %s | %s |" % (variant, threads, policy, fmt(w), fmt(med(rs, "cpu")), ratio(w, one)))
            if variant == "current" and threads == 1:
                # Amdahl's bound for issue 23's ">= 1.6 x on 2 threads": the program's time outside the injection
                # loop (start-up, reading the CT, writing the results: the process's wall time less metrics.json's
                # wall_time_s, which includes the porous-solid set-up) stays, the loop at best halves.
                loop = med(rs, "loop_s")
                outside = w - loop
                summary.append(("voxel inject 5 ml, 1 thread: the injection loop / the whole program", "%s s / %s s wall" % (fmt(loop), fmt(w)),
                                "2 threads can give at most %s x even if every pass of the loop ran on both cores with no overhead "
                                "(%s s outside the loop stays; the target 1.6 x needs it under %s s)" % (ratio(w, outside + loop / 2), fmt(outside), fmt(w / 1.6 - loop / 2)),
                                "cementsph inject ... --volume-ml 5 --threads 1 (metrics.json wall_time_s)"))
            if variant == "current" and threads == 2:
                summary.append(("voxel inject 5 ml, 2 threads / 1 thread, OMP_WAIT_POLICY %s" % policy, "%s s wall, %s s CPU" % (fmt(w), fmt(med(rs, "cpu"))),
                                "%s x the 1-thread wall time (load %.1f)" % (ratio(w, one), loads[-1]), "cementsph inject ... --volume-ml 5 --threads 2"))
    details.append("### Threads, 5 ml on the bundled phantom (the load average is the machine's, other jobs included)\n\n%s\n" % "\n".join(rows))

if want("snapshots"):
    # 4. Snapshots: the 5 ml run with the scene's 100 particle snapshots against the same run with only the final
    # one (snapshot_interval_s past the injection's end). Issue 23's target: at most 1.1 x. The current build
    # twice: its default snapshots (snapshot_arrays "growth": the cement that had arrived, each voxel written once)
    # and "flow" (every voxel's pressure, volume and velocity at every snapshot).
    rows = ["| build | snapshots | wall (s) | CPU (s) | bytes written (MB) | with / without (wall) | with / without (CPU) |", "|---|---|---|---|---|---|---|"]
    for variant, binary in (("current", CURRENT), ("baseline", BASE)):
        if not binary:
            continue
        kinds = [("100", []), ("1 (final)", ["--snapshot-interval-s", "1e6"])]
        if variant == "current":
            kinds = [("100, growth (default)", []), ("100, flow", ["--set", "snapshot_arrays=flow"]), kinds[1]]
        runs = {kind: [] for kind, _ in kinds}
        for rep in range(REPEATS):
            order = kinds if rep % 2 == 0 else list(reversed(kinds))
            for n, (kind, extra) in enumerate(order):
                tag = "snapshots-%s-%d-%d" % (variant, kinds.index((kind, extra)), rep)
                runs[kind].append(inject(binary, tag, 5, extra=extra))
        without = runs[kinds[-1][0]]
        for kind, _ in kinds:
            rs = runs[kind]
            last = kind == kinds[-1][0]
            rows.append("| %s | %s | %s | %s | %s | %s | %s |" % (variant, kind, fmt(med(rs, "wall")), fmt(med(rs, "cpu")), fmt(med(rs, "mb"), "%.0f"),
                        "" if last else ratio(med(rs, "wall"), med(without, "wall")), "" if last else ratio(med(rs, "cpu"), med(without, "cpu"))))
            if variant == "current" and not last:
                summary.append(("voxel inject 5 ml, %s snapshots / 1 snapshot" % kind, "%s s wall, %s s CPU, %s MB" % (fmt(med(rs, "wall")), fmt(med(rs, "cpu")), fmt(med(rs, "mb"), "%.0f")),
                                "%s x wall, %s x CPU (target <= 1.1 x; load %.1f)" % (ratio(med(rs, "wall"), med(without, "wall")), ratio(med(rs, "cpu"), med(without, "cpu")), loads[-1]),
                                "cementsph inject ... --volume-ml 5 %s[--snapshot-interval-s 1e6]" % ("--set snapshot_arrays=flow " if "flow" in kind else "")))
    details.append("### Snapshots, 5 ml on the bundled phantom, 1 thread (medians of %d interleaved rounds; the files are written on a second thread)\n\n%s\n" % (REPEATS, "\n".join(rows)))

if want("particles") and not QUICK:
    # 5. The incompressible SPH engine (particle-darcy) against the voxel engine on the same phantom scene, 1 thread,
    # interleaved (issue 19's speed target: within 3 x the voxel model's CPU at 5 ml). particle-darcy's cost grows
    # about as V^2 (steps ~ particles), so 5 ml takes tens of minutes: by default 0.5 and 1 ml are measured and each
    # engine's CPU growth exponent between them is reported with the 5 ml ratio it implies (marked as such);
    # PARTICLE_VOLUMES=1,5 measures 5 ml itself.
    pvols = [float(x) for x in os.environ.get("PARTICLE_VOLUMES", "0.5,1").split(",") if x.strip()]
    # Every engine of README's model table against the voxel one (ENGINES=... for fewer).
    # "paper" is the `paper` preset (--preset paper: the paper's weakly compressible particles with its time step).
    engines = [e for e in os.environ.get("ENGINES", "voxel-darcy,particle-darcy,incompressible,equation-of-state,paper").split(",") if e]
    if "voxel-darcy" not in engines:
        engines.insert(0, "voxel-darcy")
    # Issue 19 asks for solver iterations, time per solve and particles per second each as a ratio to the voxel
    # model: the unknowns are the cement points at the end (particles, or filled voxels), "points x steps per CPU
    # second" the throughput (each step moves every point), and each ratio is the engine's over voxel-darcy's.
    rows = ["| volume | engine | wall (s) | CPU (s) | CPU / voxel-darcy | steps | pressure solves | CG iterations per solve (/ voxel) | time per solve, ms (/ voxel) | points at the end | points x steps per CPU s (/ voxel) | tip pressure (Pa) |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    res = {(vol, e): [] for vol in pvols for e in engines}
    for vol in pvols:
        for rep in range(REPEATS):
            order = list(engines)
            if rep % 2:
                order.reverse()
            for engine in order:
                tag = "engine-%s-%gml-%d" % (engine, vol, rep)
                r = inject(CURRENT, tag, vol, extra=["--preset", "paper"] if engine == "paper" else ["--set", "pressure_model=%s" % engine])
                if r["rc"] == 0:
                    if r.get("steps") and r.get("solve_s") is not None:
                        r["ms_per_solve"] = 1e3 * r["solve_s"] / r["steps"]
                    if r["points"] and r["step_count"] and r["cpu"] > 0:
                        r["point_steps_per_s"] = r["points"] * r["step_count"] / r["cpu"]
                res[(vol, engine)].append(r)
        v = res[(vol, "voxel-darcy")]
        for engine in engines:
            rs = res[(vol, engine)]
            def against(key, form):
                return "%s (%s)" % (fmt(med(rs, key), form), ratio(med(rs, key), med(v, key)))
            rows.append("| %g ml | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (vol, engine, fmt(med(rs, "wall")), fmt(med(rs, "cpu")), ratio(med(rs, "cpu"), med(v, "cpu")),
                        fmt(med(rs, "step_count"), "%.0f"), fmt(med(rs, "steps"), "%.0f"), against("iterations", "%.1f"), against("ms_per_solve", "%.2f"),
                        fmt(med(rs, "points"), "%.0f"), against("point_steps_per_s", "%.3g"), fmt(med(rs, "tip_pa"), "%.1f")))
            if engine == "voxel-darcy":
                continue
            summary.append(("%s / voxel-darcy, %g ml phantom, 1 thread" % (engine, vol), "%s s / %s s CPU" % (fmt(med(rs, "cpu")), fmt(med(v, "cpu"))),
                            "%s x the voxel engine's CPU%s (load %.1f)" % (ratio(med(rs, "cpu"), med(v, "cpu")), " (target at 5 ml <= 3 x)" if engine == "particle-darcy" else "", loads[-1]),
                            "cementsph inject ... --volume-ml %g %s" % (vol, "--preset paper" if engine == "paper" else "--set pressure_model=" + engine)))
            if engine == "particle-darcy" and vol == 5:
                # Issue 19's 3 x bound from the solves alone: particle-darcy's pressure solves (its steps times its time
                # per solve, metrics.json's pressure_solve_wall_s) against the voxel engine's whole CPU time.
                summary.append(("  particle-darcy's pressure solves alone, 5 ml", "%s solves x %s ms = %s s" % (fmt(med(rs, "steps"), "%.0f"), fmt(med(rs, "ms_per_solve")), fmt(med(rs, "solve_s"))),
                                "%s x the voxel engine's whole CPU time, before any particle geometry (target <= 3 x)" % ratio(med(rs, "solve_s"), med(v, "cpu")),
                                "(the row above; metrics.json pressure_solve_wall_s)"))
    if len(pvols) >= 2 and 5 not in pvols and "particle-darcy" in engines:
        # The voxel engine at 5 ml is cheap (seconds) and is measured; only particle-darcy's 5 ml CPU is extrapolated
        # from its growth exponent (the voxel engine's own exponent at small volumes reflects its fixed costs).
        lo, hi = pvols[0], pvols[-1]
        v5 = [inject(CURRENT, "engine-voxel-darcy-5ml-%d" % rep, 5, extra=["--set", "pressure_model=voxel-darcy"]) for rep in range(REPEATS)]
        plo, phi, cv5 = med(res[(lo, "particle-darcy")], "cpu"), med(res[(hi, "particle-darcy")], "cpu"), med(v5, "cpu")
        if all(x > 0 and not math.isnan(x) for x in (plo, phi, cv5)):
            ex = math.log(phi / plo) / math.log(hi / lo)
            p5 = phi * (5 / hi) ** ex
            summary.append(("  particle-darcy at 5 ml (extrapolated)", "CPU ~ V^%.2f from %g-%g ml: %.0f s; voxel-darcy 5 ml measured %s s" % (ex, lo, hi, p5, fmt(cv5)),
                            "about %.0f x at 5 ml (extrapolated, not measured)" % (p5 / cv5), "(the rows above; --volume-ml 5 for voxel-darcy)"))
    details.append("### The particle engines against voxel-darcy on the bundled phantom, 1 thread (medians of %d interleaved rounds)\n\n%s\n" % (REPEATS, "\n".join(rows)))

if want("sph"):
    # 6. The SPH engine's step benchmark (built with -DCEMENTSPH_BUILD_BENCHMARKS=ON).
    sph = exe(BUILD, "SPHStepBenchmark")
    if sph:
        filt = "BM_PeriodicBox200k/(1|2)/(0|20)/" if QUICK else "BM_"
        js = os.path.join(OUT, "sph-step.json")
        args = [sph, "--benchmark_filter=" + filt, "--benchmark_out=" + js, "--benchmark_out_format=json",
                "--benchmark_min_time=%s" % ("0.2" if QUICK else "0.5")]
        if not QUICK:
            args += ["--benchmark_repetitions=3", "--benchmark_report_aggregates_only=true"]
        r = run(args, log=os.path.join(OUT, "sph-step.log"), env={"OMP_WAIT_POLICY": "PASSIVE"})  # not through the launcher
        bench = {}
        if r["rc"] == 0:
            for b in json.load(open(js))["benchmarks"]:
                if b.get("aggregate_name", "median") != "median":
                    continue
                name = re.sub(r"_median$", "", b["run_name"] if "run_name" in b else b["name"])
                bench[name] = b
        rows = ["| benchmark / threads / skin (% of h) | ms per step | fluid-particle-steps/s | real-time factor |", "|---|---|---|---|"]
        for name, b in sorted(bench.items()):
            ms = b["real_time"] * {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b["time_unit"]]
            rows.append("| %s | %.2f | %s | %s |" % (name.replace("/real_time", ""), ms,
                        fmt(b.get("fluid_particle_steps_per_s", float("nan")) / 1e6, "%.2f M"), fmt(b.get("real_time_factor", float("nan")), "%.1f")))
        def fps(n):
            b = bench.get(n)
            return b.get("fluid_particle_steps_per_s") if b else None
        p1, p2, p10 = fps("BM_PeriodicBox200k/1/20/real_time"), fps("BM_PeriodicBox200k/2/20/real_time"), fps("BM_PeriodicBox200k/1/0/real_time")
        summary.append(("SPH step, 205k-particle periodic box, skin 0.2 h, 2 threads", fmt((p2 or float("nan")) / 1e6, "%.2f M fluid-particle-steps/s"),
                        "2 threads / 1: %s x; skin 0.2 h / no skin (1 thread): %s x" % (ratio(p2, p1), ratio(p1, p10)), "SPHStepBenchmark --benchmark_filter=" + filt))
        i1, i2 = bench.get("BM_Injection100s/1/iterations:1/real_time"), bench.get("BM_Injection100s/2/iterations:1/real_time")
        if i1 and i2:
            summary.append(("SPH injection 5 ml over 100 s (3374 particles)", "%.1f s (1 thread), %.1f s (2 threads)" % (i1["real_time"] * 1e-3 if i1["time_unit"] == "ms" else i1["real_time"], i2["real_time"] * 1e-3 if i2["time_unit"] == "ms" else i2["real_time"]),
                            "2 threads / 1: %s x faster" % ratio(i1["real_time"], i2["real_time"]), "SPHStepBenchmark --benchmark_filter=Injection"))
        details.append("### SPH engine step benchmark (medians%s; wall time per step)\n\n%s\n" % ("" if QUICK else " of 3", "\n".join(rows)))
    else:
        details.append("### SPH engine step benchmark\n\nNot built (configure with -DCEMENTSPH_BUILD_BENCHMARKS=ON and build SPHStepBenchmark).\n")

if want("plan") and not QUICK:
    # 7. An oblique plan against the axial one (issue 20 item 5: "oblique scans plan as fast as axial ones"): the
    # vertebra phantom and its copy tilted 20 degrees about x, planned with the same request, 1 OpenMP thread, CPU
    # time. PlanObliqueTest asserts only that the two plans agree; it prints each plan's CPU time, read here.
    pot = exe(BUILD, "PlanObliqueTest")
    if pot:
        rows = ["| field | axial CPU (s) | tilted 20 deg CPU (s) | tilted / axial | per injection | injections axial / tilted |", "|---|---|---|---|---|---|"]
        per_field = {}
        for rep in range(REPEATS):
            log = os.path.join(OUT, "plan-oblique-%d.log" % rep)
            run([pot, "--gtest_filter=PlanOblique.ATilted*"], log=log)
            for m in re.finditer(r"plan on a (\S+) x (\S+) x (\S+) mm field, (\S+) / (\S+) injections, CPU: axial (\S+) s, tilted 20 deg (\S+) s \((\S+)x; per injection (\S+)x\)", open(log).read()):
                field = "%s x %s x %s mm" % m.groups()[:3]
                per_field.setdefault(field, []).append(m.groups()[3:])
        for field, rs in per_field.items():
            ax = statistics.median(float(r[2]) for r in rs)
            ti = statistics.median(float(r[3]) for r in rs)
            pi = statistics.median(float(r[5]) for r in rs)
            rows.append("| %s | %.3f | %.3f | %.2f x | %.2f x | %s / %s |" % (field, ax, ti, ti / ax, pi, rs[0][0], rs[0][1]))
            summary.append(("plan, tilted 20 deg / axial, %s field" % field, "%.3f s / %.3f s CPU" % (ti, ax),
                            "%.2f x (per injection %.2f x; target: as fast as axial; load %.1f)" % (ti / ax, pi, loads[-1]), "PlanObliqueTest --gtest_filter=PlanOblique.ATilted*"))
        details.append("### Oblique plan against axial, vertebra phantom, 1 thread (medians of %d runs of PlanObliqueTest)\n\n%s\n" % (REPEATS, "\n".join(rows)))
    else:
        details.append("### Oblique plan against axial\n\nNot built (build the PlanObliqueTest target).\n")

def peers():
    # 8. DRR and registration against their peers (plastimatch, elastix), where built; not in QUICK.
    if not QUICK and want("peers"):
        drr = exe(BUILD, "drr-bench")
        if drr:
            log = os.path.join(OUT, "drr-bench.md")
            r = run([drr, os.path.join(OUT, "drr-work"), "--repeats=5"], log=log)
            text = open(log).read()
            for m in re.finditer(r"Speed-up, DRR time.*?\): 1 thread ([\d.]+)x, 2 threads ([\d.]+)x", text):
                summary.append(("DRR 512 x 512 of a 256 x 256 x 200 CT, against plastimatch drr -i exact", "(drr-bench table)",
                                "plastimatch time / ours: %s x (1 thread), %s x (2 threads)" % m.groups(), "drr-bench DIR --repeats=5"))
                break
            for m in re.finditer(r"Speed-up, whole program.*?\): 1 thread ([\d.]+)x, 2 threads ([\d.]+)x", text):
                summary.append(("  whole program (read, DRR, write)", "(drr-bench table)", "plastimatch / ours: %s x (1 thread), %s x (2 threads)" % m.groups(), "drr-bench"))
                break
            details.append("### DRR (drr-bench, rc %d)\n\n%s\n" % (r["rc"], demote(text.strip())))
        img = exe(BUILD, "imaging-bench")
        if img:
            log = os.path.join(OUT, "imaging-bench.md")
            r = run([img, os.path.join(OUT, "imaging-work")] + os.environ["IMAGING_ARGS"].split(), log=log)
            text = open(log).read()
            ours, theirs, tre, etre = [], [], [], []
            for line in text.splitlines():
                cells = [c.strip() for c in line.strip().strip("|").split("|")]
                if len(cells) == 12 and re.match(r"^\d+$", cells[0]):
                    try:
                        ours.append(float(cells[5])); tre.append(float(cells[6]))
                        theirs.append(float(cells[8])); etre.append(float(cells[9]))
                    except ValueError:
                        pass
            if ours:
                summary.append(("affine registration, 128^3 pairs with cement, against elastix's default affine map (both given the cement mask)", "ours %.2f s, TRE %.3f-%.3f mm; elastix TRE %.3f-%.3f mm" % (statistics.median(ours), min(tre), max(tre), min(etre) if etre else float("nan"), max(etre) if etre else float("nan")),
                                "elastix time / ours: %s x (median of pairs)" % ratio(statistics.median(theirs), statistics.median(ours)) if theirs else "n/a", "imaging-bench DIR " + os.environ["IMAGING_ARGS"]))
                # elastix with tighter maps (the bench's second table): its speed against its error.
                maps = {}
                for line in text.splitlines():
                    cells = [c.strip() for c in line.strip().strip("|").split("|")]
                    if len(cells) == 4 and re.match(r"^\d+$", cells[0]):
                        try:
                            maps.setdefault(cells[1], []).append((float(cells[2]), float(cells[3])))
                        except ValueError:
                            pass
                for name, rs in maps.items():
                    t = statistics.median(x[0] for x in rs)
                    summary.append(("  elastix, %s" % name, "%.2f s, TRE %.3f-%.3f mm" % (t, min(x[1] for x in rs), max(x[1] for x in rs)),
                                    "elastix time / ours: %s x (median of pairs)" % ratio(t, statistics.median(ours)), "imaging-bench (second table)"))
            details.append("### Registration (imaging-bench %s, rc %d)\n\n%s\n" % (os.environ["IMAGING_ARGS"], r["rc"], demote(text.strip())))



try:
    peers()
except Exception as e:  # a peer's output we cannot read must not lose the figures above
    details.append("### DRR and registration\n\nNot summarised: %r\n" % e)

end_load = load()
ended = datetime.datetime.now(datetime.timezone.utc)
model = subprocess.run(["sh", "-c", "lscpu | sed -n 's/^Model name: *//p' | head -1"], capture_output=True, text=True).stdout.strip()
mem = [l for l in open("/proc/meminfo") if l.startswith("MemTotal")][0].split()[1]
rev = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True, text=True).stdout.strip()
md = []
md.append("## Benchmarks run %s UTC (%s mode%s)\n" % (started.strftime("%Y-%m-%d %H:%M"), "QUICK" if QUICK else "full",
                                                      ", only " + ", ".join(ONLY) if ONLY else ""))
md.append("Machine: %s, %d cores, %.0f GB; load average at start %s, at end %s, %.2f-%.2f over the runs (1-minute, other jobs included). "
          "Build measured: `%s` at %s; baseline: %s. %s to %s UTC.\n" % (
              model, os.cpu_count(), int(mem) / 1048576.0, "/".join("%.2f" % x for x in start_load), "/".join("%.2f" % x for x in end_load),
              min(loads), max(loads), BUILD.replace(ROOT + "/", ""), rev, ("`%s/bin/cementsph`, interleaved with it" % BASELINE) if BASE else "none given",
              started.strftime("%H:%M"), ended.strftime("%H:%M")))
md.append("| benchmark | figure | ratio | command |\n|---|---|---|---|")
for s in summary:
    md.append("| %s | %s | %s | `%s` |" % tuple(x.replace("|", "\\|") for x in s))  # a filter's | inside a cell
md.append("")
md.extend(details)
text = "\n".join(md) + "\n"
open(os.path.join(OUT, "benchmarks.md"), "w").write(text)
print(text)
PYTHON
