#!/usr/bin/env python3
"""Where the deepest stack goes: `stackchain.py ELF OUT` reads what `stackdepth.c` printed with `words=1` (the `stack`
line and the stack's words from its lowest store up), finds the longest chain of frame records (a saved r7 pointing
further up the stack, then an odd return address into the code; thumbv6m keeps frame pointers) and prints each
frame's size and the function that called it.

    qemu-system-arm ... -plugin stackdepth.so,lo=0x<__ebss>,hi=0x<_stack_start>,words=1 -kernel ELF 2> out.txt
    python3 boards/tools/stackchain.py ELF out.txt
"""
import bisect, os, re, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from disasm import disassemble

elf, out = sys.argv[1], sys.argv[2]
starts = {}
for a, _, f, _, _ in disassemble(elf, '-C'):
    starts.setdefault(f, a)
funcs = sorted((a, f) for f, a in starts.items())
addrs = [a for a, _ in funcs]
code_end = max(addrs) + 0x10000


def name(a):
    return funcs[bisect.bisect_right(addrs, a) - 1][1][:100]


words, low, pc = {}, None, None
for line in open(out):
    if line.startswith('w '):
        _, a, v = line.split()
        words[int(a, 16)] = int(v, 16)
    elif line.startswith('stack'):
        print(line.strip())
        low = int(re.search(r'lowest=(0x[0-9a-f]+)', line).group(1), 16)
        pc = int(re.search(r'pc=(0x[0-9a-f]+)', line).group(1), 16)
if not words:
    sys.exit('no stack words: run stackdepth.so with words=1')
print('lowest store in', name(pc))
top = max(words) + 4


def record(x):
    """Whether `x` holds a frame record: the caller's frame pointer (further up the stack), then a return address."""
    return (x in words and x + 4 in words and x < words[x] < top and words[x + 4] & 1
            and words[x + 4] - 1 < code_end)


best = []
for a in sorted(words):
    chain, x = [], a
    while record(x):
        chain.append((x, words[x + 4] - 1))
        x = words[x]
    if len(chain) > len(best):
        best = chain
prev = low
for x, ra in best:
    print(f'{x:#x} a frame of {x - prev:5d} bytes, called from {name(ra)}')
    prev = x
