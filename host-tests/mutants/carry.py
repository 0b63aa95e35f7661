#!/usr/bin/env python3
"""Carries mutation outcomes judged on an older commit over to the current tree's mutant names.

    python3 host-tests/mutants/carry.py OLD_COMMIT OUT.json IN.json [IN.json ...]

cargo-mutants names a mutant `file:line:col: what`, so an edit above a mutant renames it. For each outcome in the
IN files (later files override earlier ones), this finds the same mutant in `cargo mutants --list` of the working
tree: same file, same function, same replacement, and its line matched to the old one by a line diff of the file
(only unchanged lines carry). A carried `missed` is to be judged again (`mutants.py --missed-in OUT.json`); a carried
`caught` stands, as the tests only grew. Mutants of changed or new lines are not carried: judge them afresh.
Prints `carry carried=.. dropped=..` (dropped: the mutated line changed or was removed).
"""
import difflib, json, os, subprocess, sys

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
old_commit, out, ins = sys.argv[1], sys.argv[2], sys.argv[3:]
merged = {}
for f in ins:
    merged.update(json.load(open(f)))
files = sorted({n.split(":")[0] for n in merged})
listing = json.loads(subprocess.run(["cargo", "mutants", "--no-config", "--list", "--json"]
                                    + sum((["--file", f] for f in files), []),
                                    cwd=REPO, capture_output=True, text=True, check=True).stdout)
by_key = {}
for m in listing:
    by_key[(m["file"], m["span"]["start"]["line"], m["span"]["start"]["column"], m["name"].split(": ", 1)[1])] = m["name"]
line_map = {}
for f in files:
    old = subprocess.run(["git", "show", f"{old_commit}:{f}"], cwd=REPO, capture_output=True, text=True,
                         check=True).stdout.split("\n")
    new = open(os.path.join(REPO, f)).read().split("\n")
    mp = {}
    for a, b, n in difflib.SequenceMatcher(None, old, new, autojunk=False).get_matching_blocks():
        for i in range(n):
            mp[a + i + 1] = b + i + 1
    line_map[f] = mp
result, dropped = {}, 0
for name, outcome in merged.items():
    f, line, col, what = name.split(":", 3)
    nl = line_map[f].get(int(line))
    key = (f, nl, int(col), what.strip())
    if nl is None or key not in by_key:
        dropped += 1
        continue
    result[by_key[key]] = outcome
json.dump(result, open(out, "w"), indent=1)
print(f"carry carried={len(result)} dropped={dropped}")
