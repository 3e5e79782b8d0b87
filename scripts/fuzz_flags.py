#!/usr/bin/env python3
"""Fuzzes the FLAG COMBINATIONS of the rff-slam command-line tools.

Not a file-format fuzzer: every input is a valid dataset made by the tools
themselves; what varies is the command line. Each trial picks a tool
(mostly rff_slam; also rff_evaluate, rff_dead_reckoning, rff_perturb,
rff_simulate and rff_convert), starts from the required flags of its usage
line, then gives 1-5 of its own flags (read from `--helpxml`, never hard
coded) hostile or ordinary values: 0, -1, nan, inf, 1e308, 2147483647,
huge strings, the allowed words of a string flag, empty, garbage, a
directory, the input file itself, true/false, ... Some trials pass those
flags through a --flagfile instead of the command line.

Every trial runs in a fresh directory WORK/trials/current (inputs copied to
in/, outputs and the working directory in out/) under `ulimit -v 8000000`
(8 GB of address space), `ulimit -f` (2 GB per file, to protect the disk)
and `timeout 60`, one process at a time. A trial is a FINDING when:

  timeout / signal / exit N  exit code >= 124 (124 timeout, 134 abort,
                             139 segfault, ...)
  input_changed              a file an input flag names changed (the
                             deliberate "output equals input" trials give
                             an output flag the path of the input's copy)
  abort_text                 stderr says 'Check failed', 'terminate called'
                             or 'std::bad_alloc'
  output_on_failure          exit != 0 but a file was written to out/ (all
                             of out/ is new). Not counted: rff_slam's
                             documented exit 3 of --fail_on_suspect, whose
                             outputs are written on purpose
  nan_inf_output             exit 0 but an output file has a nan/inf token
  slow_success / slow_reject exit 0 after > 60 s; exit != 0 after > 30 s

Findings are deduplicated by (tool, class, key line), the key line being
the first line of stderr that is not a glog INFO line (a line with one of
the abort texts first), with numbers stripped. When stderr has nothing but
INFO lines (a solve killed by the timeout), its last line says nothing about
the cause, so the inputs and the names of the fuzzed flags join the key.
Each new distinct finding is printed at once and shrunk by dropping fuzzed
flags one at a time while the finding still reproduces; its minimal repro
is left in WORK/repro/F<n>/. Distinct findings whose minimal repros are the
same command are marked "same as".
Every finding (repeats too) is appended to WORK/findings.jsonl with its
full command, and every trial to WORK/trials.jsonl.

Run from anywhere (python3 standard library only):

  /usr/bin/python3 scripts/fuzz_flags.py --minutes 20 [--seed S] \
      [--work /tmp/fuzz_flags] [--build BUILD_DIR]

It ends with a summary: trials, CPU minutes of the children, findings per
class and each distinct finding with a minimal repro command line.
"""

import argparse
import dataclasses
import hashlib
import json
import os
import random
import re
import resource
import shlex
import shutil
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ElementTree
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SHARED_PLAZA = REPO.parent / "shared" / "data" / "plaza1"

VMEM_KB = 8000000            # ulimit -v
FILE_SIZE_BLOCKS = 2000000   # ulimit -f (1 KB blocks): 2 GB per file
TIMEOUT_S = 60
SLOW_SUCCESS_S = 60
SLOW_REJECT_S = 30
ABORT_TEXTS = ("Check failed", "terminate called", "std::bad_alloc")
GLOG_INFO = re.compile(r"^I\d+ \d")
INFO_ONLY = "(INFO lines only) "
NAN_INF = re.compile(rb"(?<![\w.])[-+]?(?:nan|inf(?:inity)?)(?!\w)", re.I)

# Tools and how often a trial picks them.
TOOL_WEIGHTS = {"rff_slam": 60, "rff_evaluate": 10, "rff_dead_reckoning": 7,
                "rff_perturb": 8, "rff_simulate": 9, "rff_convert": 6}

NUMBERS = ["0", "-1", "1", "2", "nan", "inf", "-inf", "1e-300", "1e300",
           "1e308", "2147483647", "-2147483648", "4294967296", "1e-10",
           "0.5", "3", "-0", "1e-320", "9" * 400, "1" * 5000]
INTEGERS = ["0", "-1", "1", "2", "3", "2147483647", "-2147483648",
            "4294967296", "18446744073709551615", "-0", "0x10", "9" * 400]
GARBAGE = ["garbage", "", " ", "x" * 5000, "RBF", "a,b,,c", "--help",
           "name=value", "\u00e9\u00e8", "0", "-1", "nan"]
STOPWORDS = {"the", "of", "a", "an", "and", "or", "else", "when", "with",
             "to", "at", "in", "on", "is", "by", "for", "as", "from", "no",
             "not", "be", "it", "its", "this", "that", "each", "one"}

# Datasets built at setup: name -> (weight as a --dataset/--input, how).
SIMULATED = {
    "paper_s1.rffd": (35, ["--preset=paper", "--seed=1"]),
    "paper_s2.rffd": (15, ["--preset=paper", "--seed=2"]),
    "range_no_odom.rffd": (15, ["--preset=paper", "--seed=3",
                                "--num_steps=100", "--odometry=false",
                                "--kind=range"]),
    "gp_draw.rffd": (15, ["--preset=gp_draw", "--seed=2",
                          "--num_steps=150"]),
    "laser_10hz.rffd": (4, ["--preset=laser_10hz", "--seed=1"]),
}
PLAZA_WEIGHT = 15
ESTIMATE_OF = "paper_s1.rffd"   # rff_evaluate's estimates are of this one


# ---------------------------------------------------------------- flags --

@dataclasses.dataclass
class Flag:
    name: str
    type: str
    default: str
    meaning: str
    role: str = "value"   # value, input, output


@dataclasses.dataclass
class Tool:
    name: str
    binary: Path
    flags: dict
    required: list        # [(flag, placeholder)] from the usage line
    optional: list        # [(flag, placeholder)] bracketed in the usage line


def wait_for_binary(binary, patience_s=600):
    """The build directory is shared: a binary may vanish for a moment."""
    deadline = time.time() + patience_s
    while not os.access(binary, os.X_OK):
        if time.time() > deadline:
            sys.exit(f"fuzz_flags: {binary} missing for {patience_s} s")
        time.sleep(5)


def read_helpxml(binary):
    wait_for_binary(binary)
    out = subprocess.run([str(binary), "--helpxml"], capture_output=True,
                         text=True, timeout=60).stdout
    return ElementTree.fromstring(out)


def parse_usage(usage, tool_name):
    """Required and bracketed --flag=PLACEHOLDER pairs of the usage line."""
    line = next((l for l in usage.splitlines()
                 if tool_name in l and "--" in l), usage)
    optional = re.findall(r"\[--(\w+)=([^\]\s]+)\]", line)
    required = re.findall(r"--(\w+)=(\S+)", re.sub(r"\[[^\]]*\]", "", line))
    return required, optional


def flag_role(flag, required, optional):
    """Whether a string flag names an input path, an output path or not."""
    if flag.type != "string":
        return "value"
    placeholders = dict(required + optional)
    placeholder = placeholders.get(flag.name, "")
    meaning = flag.meaning
    if placeholder.startswith("OUT") or flag.name.startswith("output") or \
            re.match(r"(Also write|Where to write|Write |Output )", meaning):
        return "output"
    if re.match(r"(IN|EST|DIR)\b", placeholder) or re.search(
            r"\.rffd|\(TUM\)|\.landmarks|Directory with|covariances of",
            meaning):
        return "input"
    return "value"


def load_tool(build, name):
    binary = build / name
    root = read_helpxml(binary)
    required, optional = parse_usage(root.findtext("usage", ""), name)
    flags = {}
    for node in root.iter("flag"):
        if "/apps/" not in node.findtext("file", ""):
            continue   # gflags' and glog's own flags: not the tools'
        flag = Flag(node.findtext("name"), node.findtext("type"),
                    node.findtext("default") or "", node.findtext("meaning"))
        flag.role = flag_role(flag, required, optional)
        flags[flag.name] = flag
    return Tool(name, binary, flags, required, optional)


def allowed_words(flag, usage_alternatives):
    """Words a string flag's help offers as values (plus some noise)."""
    words = set(usage_alternatives)
    for piece in re.split(r",|\||\bor\b|;|:|\(", flag.meaning):
        tokens = re.findall(r"[A-Za-z][A-Za-z0-9_]*", piece)
        words.update(tokens[:1] + tokens[-1:])
    words = {w for w in words if len(w) > 1 and w.lower() not in STOPWORDS}
    if flag.default:
        words.add(flag.default)
    return sorted(words)


# --------------------------------------------------------------- trials --
# A value is symbolic until a trial directory exists:
#   ("lit", text)  ("in", data name)  ("out", file name)  ("in_dir",)
#   ("out_dir",)   ("missing",)       and, for booleans, ("bare",) --name
#   and ("negated",) --noname.

@dataclasses.dataclass
class Trial:
    tool: str
    base: list                 # [(flag, value)] the usage's flags
    fuzzed: list               # [(flag, value)] what varies
    via_flagfile: bool = False

    def effective_base(self):
        fuzzed_names = {name for name, _ in self.fuzzed}
        return [(n, v) for n, v in self.base if n not in fuzzed_names]


class TrialMaker:
    """Draws random trials for the tools."""

    def __init__(self, rng, tools, data, configs):
        self.rng = rng
        self.tools = tools
        self.data = data            # name -> weight as a dataset
        self.configs = configs      # repo flagfiles
        self.avoid = set()          # (tool, flag, value) known to time out

    def dataset(self):
        names = list(self.data)
        return self.rng.choices(names, [self.data[n] for n in names])[0]

    def placeholder_value(self, tool, flag, placeholder):
        """The ordinary value of a usage placeholder, or None."""
        ext = Path(placeholder).suffix
        if placeholder.startswith("OUT"):
            return ("out", f"{flag}{ext}")
        if placeholder == "DIR":
            return ("in", "plaza1_raw")
        if placeholder.startswith("IN") or placeholder.startswith("EST"):
            if ext == ".rffd":
                return ("in", ESTIMATE_OF if tool == "rff_evaluate"
                        and self.rng.random() < 0.8 else self.dataset())
            return ("in", "estimate" + ext)
        if "configs/" in placeholder:
            return ("lit", str(self.rng.choice(self.configs)))
        if re.fullmatch(r"[a-z_]+", placeholder):
            return ("lit", placeholder)
        return None

    def base(self, tool):
        base = [(f, self.placeholder_value(tool.name, f, p))
                for f, p in tool.required]
        for flag, placeholder in tool.optional:
            value = self.placeholder_value(tool.name, flag, placeholder)
            if value and value[0] != "lit" and self.rng.random() < 0.5:
                base.append((flag, value))
        return base

    def path_value(self, tool, flag, inputs):
        r = self.rng.random()
        if flag.role == "output":
            if r < 0.6:
                return ("out", flag.name + self.rng.choice(
                    [".out", ".tum", ".json", ".rffd", ""]))
            if r < 0.75:   # output equals input: one the trial reads
                name = self.rng.choice(inputs or [self.dataset()])
                if name == "plaza1_raw":   # a file of the input directory
                    name += "/" + self.rng.choice(
                        ["Plaza1_GT.txt", "Plaza1_TD.txt", "new.rffd"])
                return ("in", name)
            return self.rng.choice([("lit", ""), ("out_dir",), ("in_dir",),
                                    ("missing",), ("lit", "x" * 5000),
                                    ("lit", "relative.txt")])
        if r < 0.5:
            usage = dict(tool.required + tool.optional)
            value = self.placeholder_value(tool.name, flag.name,
                                           usage.get(flag.name, "IN.rffd"))
            return value or ("in", self.dataset())
        return self.rng.choice(
            [("lit", ""), ("in_dir",), ("out_dir",), ("missing",),
             ("in", self.dataset()), ("in", "estimate.tum"),
             ("in", "estimate.landmarks"), ("in", "estimate.cov"),
             ("in", "plaza1_raw"), ("lit", "/dev/null"), ("lit", "x" * 5000),
             ("lit", "garbage")])

    def plain_value(self, tool, flag):
        r = self.rng.random()
        if flag.type == "bool":
            return self.rng.choice([("lit", "true"), ("lit", "false"),
                                    ("bare",), ("negated",)] +
                                   ([("lit", "maybe")] if r < 0.1 else []))
        if flag.type == "string":
            usage_words = [w for _, p in tool.required + tool.optional
                           for w in p.split("|") if "|" in p]
            if r < 0.6:
                return ("lit", self.rng.choice(allowed_words(flag,
                                                             usage_words)))
            if r < 0.85:
                return ("lit", self.rng.choice(GARBAGE))
            return self.rng.choice([("in_dir",), ("in", self.dataset())])
        if r < 0.15 and flag.default:
            return ("lit", flag.default)
        if r < 0.3 and flag.default:
            try:
                scaled = float(flag.default) * self.rng.choice([0.1, 10])
                return ("lit", repr(int(scaled)) if flag.type != "double"
                        else repr(scaled))
            except ValueError:
                pass
        integral = flag.type != "double" and r < 0.85
        return ("lit", self.rng.choice(INTEGERS if integral else NUMBERS))

    def value(self, tool, flag, inputs):
        if flag.role in ("input", "output"):
            return self.path_value(tool, flag, inputs)
        return self.plain_value(tool, flag)

    def make(self):
        names = list(TOOL_WEIGHTS)
        tool = self.tools[self.rng.choices(
            names, [TOOL_WEIGHTS[n] for n in names])[0]]
        base = self.base(tool)
        inputs = [v[1] for _, v in base if v[0] == "in"]
        count = self.rng.randint(1, min(5, len(tool.flags)))
        fuzzed = []
        for name in self.rng.sample(sorted(tool.flags), count):
            value = self.value(tool, tool.flags[name], inputs)
            if (tool.name, name, value) not in self.avoid:
                fuzzed.append((name, value))
        if tool.name == "rff_slam" and self.rng.random() < 0.1:
            fuzzed.append(("flagfile",
                           ("lit", str(self.rng.choice(self.configs)))))
        return Trial(tool.name, base, fuzzed,
                     via_flagfile=self.rng.random() < 0.2)


# -------------------------------------------------------------- running --

@dataclasses.dataclass
class Outcome:
    argv: list
    cwd: str
    flagfile_text: str
    rc: int
    wall: float
    stderr: str
    classes: list
    key: str
    evidence: str

    def command(self):
        return command_line(self.argv, self.cwd)


def command_line(argv, cwd):
    """One shell line that reproduces a run."""
    return (f"cd {shlex.quote(str(cwd))} && ulimit -v {VMEM_KB} && "
            f"timeout {TIMEOUT_S} {shlex.join(argv)}")


def copy_input(data_dir, name, in_dir):
    source, target = data_dir / name, in_dir / name
    if source.is_dir():
        shutil.copytree(source, target, dirs_exist_ok=True)
    elif source.exists() and not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
    return target   # may not exist: a new file in an input directory


def resolve(value, data_dir, tdir):
    kind = value[0]
    if kind == "lit":
        return value[1]
    if kind == "in":
        return str(copy_input(data_dir, value[1], tdir / "in"))
    return str({"out": lambda: tdir / "out" / value[1],
                "in_dir": lambda: tdir / "in",
                "out_dir": lambda: tdir / "out",
                "missing": lambda: tdir / "missing" / "file"}[kind]())


def render(name, value, data_dir, tdir):
    if value[0] == "bare":
        return f"--{name}"
    if value[0] == "negated":
        return f"--no{name}"
    return f"--{name}={resolve(value, data_dir, tdir)}"


def materialize(trial, tools, data_dir, tdir):
    """Creates the trial directory; returns (argv, flagfile text)."""
    shutil.rmtree(tdir, ignore_errors=True)
    (tdir / "in").mkdir(parents=True)
    (tdir / "out").mkdir()
    base = [render(n, v, data_dir, tdir) for n, v in trial.effective_base()]
    fuzzed = [render(n, v, data_dir, tdir) for n, v in trial.fuzzed]
    argv = [str(tools[trial.tool].binary)]
    flagfile_text = ""
    if trial.via_flagfile and fuzzed:
        flagfile_text = "".join(arg + "\n" for arg in fuzzed)
        (tdir / "flags.txt").write_text(flagfile_text, errors="surrogateescape")
        return argv + [f"--flagfile={tdir / 'flags.txt'}"] + base, \
            flagfile_text
    return argv + base + fuzzed, flagfile_text


def read_inputs(trial, tools, tdir):
    """The files of in/ that an input flag of the trial names: the files
    whose bytes must not change (other files of in/ are fair outputs)."""
    flags = tools[trial.tool].flags
    named = set()
    for name, value in trial.effective_base() + trial.fuzzed:
        if value[0] == "in" and name in flags and \
                flags[name].role == "input":
            path = tdir / "in" / value[1]
            named.update(path.rglob("*") if path.is_dir() else [path])
    return [p for p in named if p.is_file()]


def digests(paths):
    return {str(p): hashlib.sha256(p.read_bytes()).hexdigest()
            if p.is_file() else None for p in paths}


def run_limited(argv, cwd, stdout_path, stderr_path):
    """Runs argv under the memory, file size and time limits.

    A binary being relinked by a concurrent build fails to start (timeout
    exits 126 or 127, "failed to run command"): that is no finding, so the
    run is retried once the binary is back.
    """
    script = (f'ulimit -v {VMEM_KB} && ulimit -f {FILE_SIZE_BLOCKS} && '
              f'exec timeout -k 5 {TIMEOUT_S} "$@"')
    for _ in range(60):
        wait_for_binary(argv[0])
        start = time.monotonic()
        with open(stdout_path, "wb") as out, open(stderr_path, "wb") as err:
            process = subprocess.Popen(
                ["/bin/bash", "-c", script, "fuzz"] + argv, cwd=cwd,
                stdout=out, stderr=err, start_new_session=True)
            try:
                rc = process.wait(timeout=TIMEOUT_S + 30)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                rc = process.wait()
        wall = time.monotonic() - start
        if rc not in (126, 127) or b"failed to run command" not in \
                Path(stderr_path).read_bytes()[:4096]:
            break
        time.sleep(5)
    return rc, wall


def read_head_and_tail(path, size=2 << 20):
    """stderr may be huge (a solver logging for 60 s): its two ends."""
    with open(path, "rb") as f:
        data = f.read(size)
        if f.seek(0, os.SEEK_END) > 2 * size:
            f.seek(-size, os.SEEK_END)
            data += b"\n[...]\n"
        else:
            f.seek(len(data))
        data += f.read()
    return data.decode(errors="replace")


def exit_class(rc):
    if rc == 124:
        return "timeout"
    if rc < 0 or rc >= 128:
        number = -rc if rc < 0 else rc - 128
        try:
            return "signal " + signal.Signals(number).name
        except ValueError:
            return f"signal {number}"
    return f"exit {rc}"


def first_nan_inf(paths, limit=64 << 20):
    """The first line with a nan/inf token in the first `limit` bytes."""
    for path in paths:
        with open(path, "rb") as f:
            for number, line in enumerate(f.read(limit).splitlines(), 1):
                if NAN_INF.search(line):
                    return f"{path.name}:{number}: " + \
                        line.decode(errors="replace").strip()[:160]
    return ""


def key_line(stderr, work):
    lines = [l for l in stderr.splitlines() if l.strip()]
    marked = [l for l in lines if any(t in l for t in ABORT_TEXTS)]
    plain = [l for l in lines if not GLOG_INFO.match(l)]
    line = (marked or plain or lines[-1:] or [""])[0]
    if GLOG_INFO.match(line):
        line = INFO_ONLY + line
    line = line.replace(str(work), "WORK")
    return re.sub(r"\d+(\.\d+)?([eE][-+]?\d+)?", "#", line)[:240]


def documented_exit(tool, rc, stderr):
    """rff_slam --fail_on_suspect: exit 3 with the outputs written."""
    return tool == "rff_slam" and rc == 3 and "quality suspect" in stderr


def classify(tool, rc, wall, stderr, inputs_changed, outputs):
    """Finding classes of one run, most serious first; evidence text."""
    classes, evidence = [], ""
    if rc < 0 or rc >= 124:
        classes.append(exit_class(rc))
    if inputs_changed:
        classes.append("input_changed")
        evidence = "changed: " + ", ".join(inputs_changed)
    if any(t in stderr for t in ABORT_TEXTS):
        classes.append("abort_text")
    if rc != 0 and outputs and not documented_exit(tool, rc, stderr):
        classes.append("output_on_failure")
        evidence = evidence or "written: " + ", ".join(p.name for p in outputs)
    if rc == 0:
        nan_line = first_nan_inf(outputs)
        if nan_line:
            classes.append("nan_inf_output")
            evidence = evidence or nan_line
    if rc == 0 and wall > SLOW_SUCCESS_S:
        classes.append("slow_success")
    if 0 < rc < 124 and wall > SLOW_REJECT_S:
        classes.append("slow_reject")
    return classes, evidence


def execute(trial, tools, data_dir, tdir, work):
    argv, flagfile_text = materialize(trial, tools, data_dir, tdir)
    inputs = read_inputs(trial, tools, tdir)
    before = digests(inputs)
    rc, wall = run_limited(argv, tdir / "out", tdir / "stdout.txt",
                           tdir / "stderr.txt")
    stderr = read_head_and_tail(tdir / "stderr.txt")
    after = digests(inputs)
    changed = [Path(p).name for p in before if before[p] != after[p]]
    outputs = sorted(p for p in (tdir / "out").rglob("*") if p.is_file())
    classes, evidence = classify(trial.tool, rc, wall, stderr, changed,
                                 outputs)
    return Outcome(argv, str(tdir / "out"), flagfile_text, rc, wall, stderr,
                   classes, key_line(stderr, work), evidence)


# ------------------------------------------------------------ the fuzzer --

def shape(trial):
    """The inputs and the fuzzed flags' names: what a trial is about."""
    inputs = sorted(v[1] for _, v in trial.effective_base() if v[0] == "in")
    return tuple(inputs + sorted(name for name, _ in trial.fuzzed))


def dedup_key(trial, outcome):
    key = (trial.tool, outcome.classes[0], outcome.key)
    return key + shape(trial) if outcome.key.startswith(INFO_ONLY) else key


def reproduces(key, outcome):
    if not outcome.classes or outcome.classes[0] != key[1]:
        return False
    # A timeout's last words vary from run to run; its class is enough.
    return key[1] in ("timeout", "slow_success", "slow_reject") or \
        outcome.key == key[2]


class Fuzzer:
    def __init__(self, args):
        self.rng = random.Random(args.seed)
        self.work = Path(args.work).resolve()
        self.build = Path(args.build).resolve()
        self.data_dir = self.work / "data"
        self.trial_dir = self.work / "trials" / "current"
        self.deadline = None
        self.minutes = args.minutes
        self.trials = 0
        self.reruns = 0
        self.class_counts = {}
        self.distinct = {}         # dedup key -> finding dict
        self.documented_exits = 0
        self.exit_codes = {}       # tool -> {rc: count}

    # Setup ---------------------------------------------------------------

    def setup(self):
        self.work.mkdir(parents=True, exist_ok=True)
        for stale in ("trials", "repro", "data"):
            shutil.rmtree(self.work / stale, ignore_errors=True)
        self.data_dir.mkdir()
        for log in ("findings.jsonl", "trials.jsonl"):
            (self.work / log).unlink(missing_ok=True)
        self.tools = {name: load_tool(self.build, name)
                      for name in TOOL_WEIGHTS}
        weights = {}
        for name, (weight, flags) in SIMULATED.items():
            self.make_data("rff_simulate", flags +
                           [f"--output={self.data_dir / name}"])
            weights[name] = weight
        if SHARED_PLAZA.is_dir():
            shutil.copytree(SHARED_PLAZA, self.data_dir / "plaza1_raw")
            self.make_data("rff_convert", [
                "--format=plaza", f"--input={self.data_dir / 'plaza1_raw'}",
                f"--output={self.data_dir / 'plaza1.rffd'}"])
        else:
            del self.tools["rff_convert"]
            shutil.copy2(REPO / "data" / "plaza1.rffd", self.data_dir)
        weights["plaza1.rffd"] = PLAZA_WEIGHT
        self.make_data("rff_slam", [
            f"--dataset={self.data_dir / ESTIMATE_OF}",
            f"--output_trajectory={self.data_dir / 'estimate.tum'}",
            f"--output_landmarks={self.data_dir / 'estimate.landmarks'}",
            f"--output_covariance={self.data_dir / 'estimate.cov'}"])
        configs = sorted((REPO / "configs").glob("*.flags"))
        self.maker = TrialMaker(self.rng, self.tools, weights, configs)
        for tool in self.tools.values():
            print(f"{tool.name}: {len(tool.flags)} flags; usage requires "
                  f"{tool.required}; outputs "
                  f"{[f.name for f in tool.flags.values() if f.role == 'output']}"
                  f"; inputs "
                  f"{[f.name for f in tool.flags.values() if f.role == 'input']}")

    def make_data(self, tool, flags):
        binary = self.build / tool
        wait_for_binary(binary)
        result = subprocess.run([str(binary)] + flags, capture_output=True,
                                text=True, cwd=self.data_dir)
        if result.returncode != 0:
            sys.exit(f"fuzz_flags: setup failed: {tool} {flags}\n"
                     f"{result.stderr[-2000:]}")

    # Trials --------------------------------------------------------------

    def run(self):
        self.deadline = time.monotonic() + self.minutes * 60
        while time.monotonic() < self.deadline:
            trial = self.maker.make()
            outcome = execute(trial, self.tools, self.data_dir,
                              self.trial_dir, self.work)
            self.trials += 1
            self.record_trial(trial, outcome)
            if outcome.classes:
                self.record_finding(trial, outcome)
            if self.trials % 50 == 0:
                print(f"[{self.trials} trials, "
                      f"{len(self.distinct)} distinct findings]", flush=True)
        shutil.rmtree(self.trial_dir, ignore_errors=True)

    def record_trial(self, trial, outcome):
        if documented_exit(trial.tool, outcome.rc, outcome.stderr):
            self.documented_exits += 1
        codes = self.exit_codes.setdefault(trial.tool, {})
        codes[outcome.rc] = codes.get(outcome.rc, 0) + 1
        with open(self.work / "trials.jsonl", "a") as log:
            log.write(json.dumps({
                "trial": self.trials, "tool": trial.tool, "rc": outcome.rc,
                "wall_s": round(outcome.wall, 3), "classes": outcome.classes,
                "key": outcome.key, "argv": outcome.argv, "flagfile": outcome.flagfile_text}) +
                "\n")

    def record_finding(self, trial, outcome):
        key = dedup_key(trial, outcome)
        for cls in outcome.classes:
            self.class_counts[cls] = self.class_counts.get(cls, 0) + 1
        new = key not in self.distinct
        entry = {"trial": self.trials, "tool": trial.tool,
                 "class": outcome.classes[0], "classes": outcome.classes,
                 "key": outcome.key, "rc": outcome.rc,
                 "wall_s": round(outcome.wall, 3), "evidence": outcome.evidence,
                 "argv": outcome.argv, "flagfile": outcome.flagfile_text,
                 "command": outcome.command(),
                 "stderr_tail": outcome.stderr[-1500:], "new": new}
        with open(self.work / "findings.jsonl", "a") as log:
            log.write(json.dumps(entry) + "\n")
        if not new:
            self.distinct[key]["count"] += 1
            return
        print(f"\nFINDING [{entry['class']}] {trial.tool} rc={outcome.rc} "
              f"{outcome.wall:.1f}s\n  key: {outcome.key}\n"
              f"  evidence: {outcome.evidence}\n  command: {entry['command']}",
              flush=True)
        if outcome.flagfile_text:
            print("  flagfile:\n    " +
                  outcome.flagfile_text.strip().replace("\n", "\n    "))
        entry["count"] = 1
        self.distinct[key] = entry
        self.shrink(trial, key, entry)

    # Shrinking -----------------------------------------------------------

    def shrink(self, trial, key, entry):
        """Fewest fuzzed flags (and no flagfile) that still reproduce.

        Tries each fuzzed flag alone first, then drops flags one at a time.
        Runs in WORK/repro/F<n>, which is left holding the minimal repro.
        Stops early at the deadline (a timeout costs 60 s per rerun).
        """
        tdir = self.work / "repro" / f"F{len(self.distinct)}"
        current, best, confirmed = trial, None, False

        def attempt(candidate):
            self.reruns += 1
            outcome = execute(candidate, self.tools, self.data_dir, tdir,
                              self.work)
            return outcome if reproduces(key, outcome) else None

        def candidates(t):
            singles = [[f] for f in t.fuzzed] if len(t.fuzzed) > 2 else []
            drops = [t.fuzzed[:i] + t.fuzzed[i + 1:]
                     for i in range(len(t.fuzzed))]
            found = [dataclasses.replace(t, fuzzed=f) for f in singles + drops]
            if t.via_flagfile:
                found.append(dataclasses.replace(t, via_flagfile=False))
            return found

        progress = True
        while progress and time.monotonic() < self.deadline:
            progress = False
            for candidate in candidates(current):
                outcome = attempt(candidate)
                if outcome:
                    current, best, confirmed = candidate, outcome, True
                    progress = True
                    break
        if not confirmed:
            best = attempt(current)
            confirmed = best is not None
        argv, flagfile_text = materialize(current, self.tools, self.data_dir,
                                          tdir)
        self.save_repro(current, key, entry, best, argv, flagfile_text,
                        tdir, confirmed)

    def save_repro(self, trial, key, entry, outcome, argv, flagfile_text,
                   tdir, confirmed):
        entry["id"] = tdir.name
        entry["repro"] = command_line(argv, tdir / "out")
        entry["repro_flagfile"] = flagfile_text
        entry["reproduced"] = confirmed
        entry["fuzzed_flags"] = len(trial.fuzzed)
        entry["minimal"] = json.dumps([trial.tool, key[1], trial.via_flagfile,
                                       trial.effective_base(),
                                       sorted(trial.fuzzed)])
        entry["same_as"] = next(
            (e["id"] for e in self.distinct.values() if e is not entry and
             e.get("minimal") == entry["minimal"]), None)
        shown = outcome if confirmed else None
        entry["repro_rc"] = shown.rc if shown else entry["rc"]
        entry["repro_wall_s"] = round(shown.wall, 2) if shown \
            else entry["wall_s"]
        entry["repro_key"] = shown.key if shown else entry["key"]
        entry["repro_evidence"] = shown.evidence if shown \
            else entry["evidence"]
        if len(trial.fuzzed) == 1 and key[1] in ("timeout", "slow_reject",
                                                 "slow_success"):
            name, value = trial.fuzzed[0]
            self.maker.avoid.add((trial.tool, name, value))
        print(f"  {entry['id']} minimal: {len(trial.fuzzed)} fuzzed flag(s), "
              f"reproduced={confirmed}, rc={entry['repro_rc']}, "
              f"{entry['repro_wall_s']}s, same as: {entry['same_as']}\n"
              f"  repro: {entry['repro']}", flush=True)
        if flagfile_text:
            print("  repro flagfile:\n    " +
                  flagfile_text.strip().replace("\n", "\n    "))

    # Summary -------------------------------------------------------------

    def summary(self):
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu_minutes = (usage.ru_utime + usage.ru_stime) / 60
        lines = ["", "=" * 72, "SUMMARY",
                 f"trials: {self.trials} (plus {self.reruns} shrink/repro "
                 f"runs); child CPU: {cpu_minutes:.2f} CPU-minutes",
                 f"documented rff_slam exit 3 (--fail_on_suspect) with "
                 f"outputs, not counted: {self.documented_exits}",
                 "exit codes per tool: " + json.dumps(
                     {t: dict(sorted(c.items()))
                      for t, c in sorted(self.exit_codes.items())}),
                 "findings per class (all trials): " +
                 json.dumps(self.class_counts, sort_keys=True),
                 f"distinct findings: {len(self.distinct)}"]
        for entry in self.distinct.values():
            lines += [f"{entry['id']} [{entry['class']}] {entry['tool']} "
                      f"seen {entry['count']}x; repro rc={entry['repro_rc']} "
                      f"{entry['repro_wall_s']}s "
                      f"reproduced={entry['reproduced']}"
                      + (f" (same as {entry['same_as']})"
                         if entry["same_as"] else ""),
                      f"  key: {entry['repro_key'] or entry['key']}",
                      f"  evidence: {entry['repro_evidence']}",
                      f"  repro: {entry['repro']}"]
            if entry["repro_flagfile"]:
                lines.append("  flagfile: " + entry["repro_flagfile"].strip()
                             .replace("\n", " | "))
        text = "\n".join(lines)
        print(text)
        (self.work / "summary.txt").write_text(text + "\n")
        with open(self.work / "distinct_findings.json", "w") as out:
            json.dump(list(self.distinct.values()), out, indent=1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", type=float, default=20,
                        help="wall time of the trials (default 20)")
    parser.add_argument("--seed", type=int, default=None,
                        help="random seed (default: from the clock)")
    parser.add_argument("--work", default="/tmp/fuzz_flags",
                        help="scratch directory (default /tmp/fuzz_flags)")
    parser.add_argument("--build", default=str(REPO / "build"),
                        help="directory of the built tools")
    args = parser.parse_args()
    if args.seed is None:
        args.seed = int(time.time())
    print(f"fuzz_flags: seed {args.seed}, {args.minutes} min, "
          f"work {args.work}", flush=True)
    fuzzer = Fuzzer(args)
    fuzzer.setup()
    try:
        fuzzer.run()
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
    fuzzer.summary()


if __name__ == "__main__":
    main()
