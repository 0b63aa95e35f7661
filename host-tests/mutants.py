#!/usr/bin/env python3
"""Mutation run over the core's arithmetic: cargo-mutants generates the mutants (`cargo mutants --list --json`, with
its filters), and this applies each one in a scratch git worktree and runs the tests that judge the core against the
f64 reference (cargo-mutants itself runs only the mutated package's tests, and the judging tests live in host-tests).

    python3 host-tests/mutants.py OUT.json [--jobs N] [--missed-in PREV.json] [cargo-mutants filters, e.g. --file src/edge.rs]

Each mutant is judged first by the core's own unit tests (`cargo test -p wraster --lib`, about a second, with every
feature and again without `bias`, whose `cfg(not(...))` code only that build compiles), then, if
they pass, by `host-tests/mutants/judge.rs`: every test file of host-tests/tests but the property tests, the commands
and the firmware runs, built as one binary (a package of its own, so host-tests' binaries are not rebuilt) in the
`mutants` profile (opt-level 1, overflow checks on, no debug info): 15 to 40 s a mutant on a 2-core VM.
`--jobs N` judges N mutants at once, each in its own worktree (/tmp/wraster-mutants-<i>, i counted from
$MUTANTS_WORKTREE_BASE, default 0); `--missed-in PREV.json` judges again only the mutants PREV.json lists as missed
(after new tests); MUTANTS_ALSO=A.json,B.json skips mutants other runs have judged. Worktrees check out HEAD.

A mutant is caught when a test fails, missed when every test passes, a timeout when the tests run past the limit
(counted as caught: the mutant changed behaviour), unviable when it does not compile. OUT.json keeps the outcomes, so
an interrupted run resumes; the last line is `mutants caught=.. missed=.. timeout=.. unviable=.. total=..`.
"""
import json, os, signal, subprocess, sys, threading, time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMEOUT = 60
UNIT = ["cargo", "test", "--profile", "mutants", "-p", "wraster", "--all-features", "--lib"]
# The unit tests again in a build without `bias`: code under `cfg(not(feature = "bias"))` is compiled only there.
UNIT_NO_BIAS = ["cargo", "test", "--profile", "mutants", "-p", "wraster", "--features", "scenes,gouraud,lighting",
                "--lib"]
JUDGE = ["cargo", "test", "--profile", "mutants", "-p", "wraster-mutants-judge", "--test", "judge"]


def run(cmd, cwd, timeout=None):
    # In a session of its own, so a timeout kills the test binary too, not only cargo (a mutant that loops would
    # otherwise keep a core busy after its verdict).
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        return p.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        return "timeout"


def built(cmd, cwd):
    return run(cmd + ["--no-run"], cwd) == 0


def judge(m, wt):
    path = os.path.join(wt, m["file"])
    orig = open(path).read()
    lines = orig.split("\n")
    s, e = m["span"]["start"], m["span"]["end"]
    # span columns are 1-based, end exclusive; lines 1-based
    start = sum(len(l) + 1 for l in lines[: s["line"] - 1]) + s["column"] - 1
    end = sum(len(l) + 1 for l in lines[: e["line"] - 1]) + e["column"] - 1
    open(path, "w").write(orig[:start] + m["replacement"] + orig[end:])
    try:
        if not built(UNIT, wt):
            return "unviable"
        r = run(UNIT, wt, TIMEOUT)
        if r == 0:
            if not built(UNIT_NO_BIAS, wt):
                return "unviable"
            r = run(UNIT_NO_BIAS, wt, TIMEOUT)
        if r == 0:
            if not built(JUDGE, wt):
                return "unviable"
            r = run(JUDGE, wt, TIMEOUT)
        return "missed" if r == 0 else ("timeout" if r == "timeout" else "caught")
    finally:
        open(path, "w").write(orig)


# The test files the judge leaves out (the property tests, the commands, the firmware runs); every other file of
# host-tests/tests must be one of judge.rs's modules, or mutants it would catch are judged missed.
NOT_JUDGED = {"commands.rs", "firmware.rs", "plan.rs", "precision_cmd.rs", "props.rs"}


def unjudged_tests():
    """The files of host-tests/tests that are neither judge.rs modules nor left out on purpose."""
    judge = open(os.path.join(REPO, "host-tests", "mutants", "judge.rs")).read()
    files = sorted(f for f in os.listdir(os.path.join(REPO, "host-tests", "tests")) if f.endswith(".rs"))
    return [f for f in files if f not in NOT_JUDGED and f'#[path = "../tests/{f}"]' not in judge]


def main():
    missing = unjudged_tests()
    assert not missing, f"host-tests/tests files the judge does not build: {missing} (add them to judge.rs)"
    args = sys.argv[1:]
    out = args.pop(0)
    jobs, only = 1, None
    while args[:1] in (["--jobs"], ["--missed-in"]):
        if args[0] == "--jobs":
            jobs = int(args[1])
        else:
            only = {k for k, v in json.load(open(args[1])).items() if v == "missed"}
        args = args[2:]
    listing = subprocess.run(["cargo", "mutants", "--no-config", "--list", "--json"] + args, cwd=REPO,
                             capture_output=True, text=True, check=True).stdout
    mutants = [m for m in json.loads(listing) if only is None or m["name"] in only]
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True).stdout.strip()
    results = json.load(open(out)) if os.path.exists(out) else {}
    # Mutants another run (MUTANTS_ALSO: its OUT.json files, comma-separated) has judged are skipped.
    done = set(results)
    for other in filter(None, os.environ.get("MUTANTS_ALSO", "").split(",")):
        if os.path.exists(other):
            done |= set(json.load(open(other)))
    todo = [m for m in mutants if m["name"] not in done]
    lock = threading.Lock()

    def worker(i):
        wt = f"/tmp/wraster-mutants-{i + int(os.environ.get('MUTANTS_WORKTREE_BASE', '0'))}"
        if not os.path.isdir(wt):
            subprocess.run(["git", "worktree", "add", "--detach", wt, head], cwd=REPO, check=True,
                           stdout=subprocess.DEVNULL)
        subprocess.run(["git", "checkout", "-q", "-f", "--detach", head], cwd=wt, check=True)
        assert run(UNIT, wt) == 0 and run(UNIT_NO_BIAS, wt) == 0 and run(JUDGE, wt) == 0, "the unmutated tree must pass"
        while True:
            with lock:
                if not todo:
                    return
                m = todo.pop(0)
            t0 = time.time()
            outcome = judge(m, wt)
            with lock:
                results[m["name"]] = outcome
                print(f"{outcome:8} {time.time() - t0:5.0f}s {m['name']}", flush=True)
                json.dump(results, open(out, "w"), indent=1)

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(jobs)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    counts = {k: sum(1 for v in results.values() if v == k) for k in ["caught", "missed", "timeout", "unviable"]}
    print("mutants " + " ".join(f"{k}={v}" for k, v in counts.items()) + f" total={len(results)}")


main()
