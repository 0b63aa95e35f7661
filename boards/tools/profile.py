#!/usr/bin/env python3
"""Instruction-level profile of a board run: `profile.py ELF COUNTS [N]` joins insncount's per-PC counts with the
disassembly (llvm-objdump) and prints per-function totals and the N hottest instructions. Instructions, not cycles."""
import os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from disasm import disassemble

elf, counts = sys.argv[1], sys.argv[2]
top = int(sys.argv[3]) if len(sys.argv) > 3 else 60
dis, func, src = {}, {}, {}
for a, text, f, path, line in disassemble(elf, '-C'):
    if path == '?':
        where = '?'
    else:
        where = ('wraster/' + path.split('/src/')[-1] if '/work/' in path and '/boards/' not in path else path.split('/')[-1]) + ':' + line
    dis[a], func[a], src[a] = text.split('@')[0].strip(), f, where
cnt = {}
for line in open(counts):
    a, c = line.split()
    cnt[int(a, 16)] = int(c)
total = sum(cnt.values())
print(f'total {total} instructions')
per = {}
for a, c in cnt.items():
    per[func.get(a, '?')] = per.get(func.get(a, '?'), 0) + c
for f, c in sorted(per.items(), key=lambda x: -x[1])[:12]:
    print(f'{c:>12} {100 * c / total:5.1f}%  {f[:100]}')
print('by source line (DWARF; inlined code counts for the line it came from):')
lines = {}
for a, c in cnt.items():
    lines[src.get(a, '?')] = lines.get(src.get(a, '?'), 0) + c
for l, c in sorted(lines.items(), key=lambda x: -x[1])[:25]:
    print(f'{c:>12} {100 * c / total:5.1f}%  {l}')
print('hottest instructions, in address order:')
hot = sorted(sorted(cnt, key=lambda a: -cnt[a])[:top])
for a in hot:
    print(f'{a:8x} {cnt[a]:>10}  {dis.get(a, "?")}')
