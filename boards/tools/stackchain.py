#!/usr/bin/env python3
"""Where the deepest stack goes: `stackchain.py ELF OUT` reads stackchain.c's output (the `stack` line and the stack's
words at its lowest point), finds the longest chain of frame records (saved r7 pointing further up the stack, then an
odd return address into .text) and prints each frame's size and the function it returns into."""
import bisect, os, re, subprocess, sys
sysroot = subprocess.run(['rustc', '--print', 'sysroot'], capture_output=True, text=True).stdout.strip()
objdump = next(os.path.join(r, 'llvm-objdump') for r, _, fs in os.walk(sysroot) if 'llvm-objdump' in fs)
dis = subprocess.run([objdump, '-d', '--no-show-raw-insn', '-C', sys.argv[1]], capture_output=True, text=True).stdout
funcs=[]
for line in dis.splitlines():
    m=re.match(r'^([0-9a-f]+) <(.*)>:$', line)
    if m: funcs.append((int(m.group(1),16), m.group(2)))
funcs.sort(); addrs=[a for a,_ in funcs]
def fn(a):
    i=bisect.bisect_right(addrs,a)-1; return funcs[i][1][:100]
mem={}; low=None; hi=None
for line in open(sys.argv[2]):
    if line.startswith('w '):
        _,a,v=line.split(); mem[int(a,16)]=int(v,16)
    elif line.startswith('stack'):
        print(line.strip()); low=int(re.search(r'lowest=(0x[0-9a-f]+)',line).group(1),16); pc=int(re.search(r'pc=(0x[0-9a-f]+)',line).group(1),16)
print('pc in', fn(pc))
hi=max(mem)+4
# find candidate frame pointer chains: start at each word a where mem[a] is a stack addr > a and mem[a+4] odd text
best=[]
for a in sorted(mem):
    chain=[]; x=a
    while x in mem and x+4 in mem and low<=mem[x]<hi and mem[x]>x and (mem[x+4]&1) and mem[x+4]<0x40000:
        chain.append((x, mem[x+4]-1)); x=mem[x]
    if len(chain)>len(best): best=chain
prev=low
for x,ra in best:
    print(hex(x), f'a frame of {x-prev:5d} bytes, called from', fn(ra)); prev=x
