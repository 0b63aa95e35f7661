#!/usr/bin/env python3
"""Mutation run over the core's arithmetic: cargo-mutants generates the mutants (`cargo mutants --list --json`, with
its filters), and this applies each one in a scratch git worktree and runs the tests that judge the core against the
f64 reference (cargo-mutants itself runs only the mutated package's tests, and the judging tests live in host-tests).

    python3 host-tests/mutants.py OUT.json [cargo-mutants filter args, e.g. --file src/edge.rs --re slope_bias]

A mutant is caught when the build or a test fails, missed when every test passes, a timeout when the tests run
past the limit (counted as caught: the mutant changed behaviour), unviable when it does not compile.
"""
import json, os, subprocess, sys, time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WT = "/tmp/wraster-mutants"
TESTS = ["boundaries", "bias", "reference", "stiff", "mock_display", "bad_input", "fixed_input", "formats",
         "gouraud", "clip", "fuzz_regressions"]
TIMEOUT = 600

def run(cmd, cwd, timeout=None):
    try:
        return subprocess.run(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              timeout=timeout).returncode
    except subprocess.TimeoutExpired:
        return "timeout"

def main():
    out, filters = sys.argv[1], sys.argv[2:]
    listing = subprocess.run(["cargo", "mutants", "--no-config", "--list", "--json"] + filters, cwd=REPO,
                             capture_output=True, text=True, check=True).stdout
    mutants = json.loads(listing)
    if not os.path.isdir(WT):
        subprocess.run(["git", "worktree", "add", "--detach", WT, "HEAD"], cwd=REPO, check=True)
    subprocess.run(["git", "checkout", "--detach", subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO,
                    capture_output=True, text=True).stdout.strip()], cwd=WT, check=True)
    test_cmd = ["cargo", "test", "--release", "-p", "host-tests"] + sum([["--test", t] for t in TESTS], [])
    lib_cmd = ["cargo", "test", "--release", "-p", "wraster", "--lib"]
    assert run(test_cmd, WT) == 0 and run(lib_cmd, WT) == 0, "the unmutated tree must pass"
    results = json.load(open(out)) if os.path.exists(out) else {}
    for m in mutants:
        name = m["name"]
        if name in results:
            continue
        path = os.path.join(WT, m["file"])
        orig = open(path).read()
        lines = orig.split("\n")
        s, e = m["span"]["start"], m["span"]["end"]
        # span columns are 1-based, end exclusive; lines 1-based
        start = sum(len(l) + 1 for l in lines[: s["line"] - 1]) + s["column"] - 1
        end = sum(len(l) + 1 for l in lines[: e["line"] - 1]) + e["column"] - 1
        open(path, "w").write(orig[:start] + m["replacement"] + orig[end:])
        t0 = time.time()
        try:
            if run(["cargo", "build", "--release", "-p", "wraster", "--all-features"], WT) != 0:
                outcome = "unviable"
            else:
                r = run(lib_cmd, WT, TIMEOUT)
                if r == 0:
                    r = run(test_cmd, WT, TIMEOUT)
                outcome = "missed" if r == 0 else ("timeout" if r == "timeout" else "caught")
        finally:
            open(path, "w").write(orig)
        results[name] = outcome
        print(f"{outcome:8} {time.time() - t0:5.0f}s {name}", flush=True)
        json.dump(results, open(out, "w"), indent=1)
    counts = {k: sum(1 for v in results.values() if v == k) for k in ["caught", "missed", "timeout", "unviable"]}
    print("mutants " + " ".join(f"{k}={v}" for k, v in counts.items()) + f" total={len(results)}")

main()
