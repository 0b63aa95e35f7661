#!/usr/bin/env python3
"""The mutation run's figures: merges the outcome files `host-tests/mutants.py` wrote (later files override earlier
ones for the same mutant, so a second judging after new tests counts) and prints a table per source file, then every
mutant still missed. Names are cargo-mutants' (`file:line:col: what`), from the commit each file was judged on.

    python3 host-tests/mutants/summary.py host-tests/mutants/results/*.json
"""
import collections, json, sys

merged = {}
for f in sys.argv[1:]:
    merged.update(json.load(open(f)))
kinds = ["caught", "timeout", "unviable", "missed"]
per = collections.defaultdict(collections.Counter)
for name, outcome in merged.items():
    per[name.split(":")[0]][outcome] += 1
print("| file | mutants | " + " | ".join(kinds) + " |")
print("|---|---|" + "---|" * len(kinds))
for f in sorted(per):
    c = per[f]
    print(f"| `{f}` | {sum(c.values())} | " + " | ".join(str(c[k]) for k in kinds) + " |")
tot = collections.Counter(merged.values())
print(f"| all | {len(merged)} | " + " | ".join(str(tot[k]) for k in kinds) + " |")
print()
for name in sorted(k for k, v in merged.items() if v == "missed"):
    print("missed", name)
print("mutants " + " ".join(f"{k}={tot[k]}" for k in kinds) + f" total={len(merged)}")
