#!/usr/bin/env python3
"""`.text` bytes of a firmware by the source file each instruction comes from (DWARF line info, so code inlined into
the board's main is still counted for the crate it came from): `text_share.py ELF`. Prints bytes per group:
wraster (src/ of this repository), compiler_builtins (64/128-bit division and friends), and the rest."""
import os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from disasm import disassemble

elf = sys.argv[1]
root = os.path.realpath(os.path.join(os.path.dirname(__file__), '..', '..', 'src')) + '/'
rows = [(a, path, func) for a, _, func, path, _ in disassemble(elf, '--section=.text')]
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
