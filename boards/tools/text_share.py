#!/usr/bin/env python3
"""`.text` bytes of a firmware by the source file each instruction comes from (DWARF line info, so code inlined into
the board's main is still counted for the crate it came from): `text_share.py ELF`. Prints bytes per group:
wraster (src/ of this repository), compiler_builtins (64/128-bit division and friends), and the rest."""
import glob, os, re, subprocess, sys

elf = sys.argv[1]
tools = glob.glob(os.path.expanduser('~/.rustup/toolchains/*/lib/rustlib/*/bin/llvm-objdump'))
objdump = tools[0] if tools else 'llvm-objdump'
root = os.path.realpath(os.path.join(os.path.dirname(__file__), '..', '..', 'src')) + '/'
out = subprocess.run([objdump, '-d', '-l', '--no-show-raw-insn', '--section=.text', elf], capture_output=True, text=True).stdout
src, func, rows = '?', '?', []
for line in out.splitlines():
    m = re.match(r'^[0-9a-f]+ <(.*)>:', line)
    if m:
        func, src = m.group(1), '?'
        continue
    m = re.match(r'^; (/.*?):\d+', line)
    if m:
        src = m.group(1)
        continue
    m = re.match(r'\s*([0-9a-f]+):', line)
    if m:
        rows.append((int(m.group(1), 16), src, func))
groups = {}
for (a, s, f), (b, _, _) in zip(rows, rows[1:] + [(rows[-1][0] + 2, '', '')]):
    size = min(b - a, 4)
    if s.startswith(root):
        g = 'wraster'
    elif 'compiler_builtins' in f or f.startswith('__aeabi') or f.startswith('__') and 'div' in f:
        g = 'compiler_builtins'
    else:
        g = 'other'
    groups[g] = groups.get(g, 0) + size
for g in ('wraster', 'compiler_builtins', 'other'):
    print(f'{g}={groups.get(g, 0)}', end=' ')
print()
