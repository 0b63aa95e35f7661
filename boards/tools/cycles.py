#!/usr/bin/env python3
"""Estimated cycles beside the boards' instruction counts: `cycles.py BOARD [--recip NAME] [--together] [SCENE ...]`
(BOARD qemu-m4 or qemu-m0; default scenes big overdraw small terrain). For each scene it builds the board with only one
strategy and only that scene (`--features size-probe`, `ONLY=<scene>`; the board's default strategy, or the one
`--recip` names, by the build-time `RECIP`: fast, fast-div, lerp64 (the exact tier), prev-pixel, f32-div on the M4),
runs it under QEMU with the insncount plugin (insncount.c in this folder; built here if missing), weights every
executed instruction by its class from the core's timing table, and prints, last for each scene,
  cycles board=<b> scene=<s> instructions=<n> instr_per_px=.. instr_per_fragment=.. instr_per_tri=.. cpi=.. est_cycles_per_px=.. est_cycles_per_fragment=.. est_cycles_per_tri=..
With `--together` it builds and runs the four scenes in one firmware instead and prints one line over them (the
report's figures, instructions per written pixel over the four scenes):
  cycles board=<b> recip=<r> scenes=4 instructions=<n> pixels=<p> instr_per_px=.. cpi=.. est_cycles_per_px=..
`instructions` is the board's own count for the draw calls (its bench line); the estimate multiplies it by the
cycles per instruction of the draw code (instructions outside the board crate, the start-up code, the clears and the
formatting). These are ESTIMATES: QEMU counts instructions, not cycles; the tables do not model flash or RAM wait
states, bus contention, or pipeline refills beyond the branch penalty; a conditional branch counts as taken for the
share of its executions its fall-through did not follow.
Tables: Cortex-M4 Technical Reference Manual, instruction timings (branch penalty P = 2: taken 3, not taken 1; SDIV and
UDIV 12, their worst case; LDR 2, STR 1, LDM/STM/PUSH/POP 1 + n; VDIV 14; VMLA/VFMA 3). Cortex-M0+ Technical
Reference Manual (DDI0484C, table 3.1) with the single-cycle multiplier the RP2040 has (MULS 1; loads and stores 2; taken
branch 2, BL 3, BX/BLX 2; PUSH/POP/LDM/STM 1 + n). The QEMU M0 board is a Cortex-M0 (taken branches one cycle more
there): the M0+ table is used because the RP2040 is the M0+ this crate targets."""
import os, re, subprocess, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from disasm import disassemble

here = os.path.dirname(os.path.abspath(__file__))
boards = os.path.dirname(here)
args = sys.argv[1:]
board = args.pop(0)
recip = None
if '--recip' in args:
    i = args.index('--recip')
    recip = args[i + 1]
    del args[i:i + 2]
together = '--together' in args
args = [a for a in args if a != '--together']
scenes = args or ['big', 'overdraw', 'small', 'terrain']
core = {'qemu-m4': 'm4', 'qemu-m0': 'm0p'}[board]
target = {'m4': 'thumbv7em-none-eabihf', 'm0p': 'thumbv6m-none-eabi'}[core]
qemu = {'m4': ['qemu-system-arm', '-cpu', 'cortex-m4', '-machine', 'mps2-an386'],
        'm0p': ['qemu-system-arm', '-machine', 'microbit']}[core]
plugin = os.path.join('/tmp', 'wraster-insncount.so')
if not os.path.exists(plugin):
    subprocess.run(['cc', '-shared', '-DQEMU_PLUGIN_VERSION=4', '-fPIC', '-O2', '-o', plugin,
                    os.path.join(here, 'insncount.c')], check=True)


def cycles_of(mn, ops, taken):
    """Cycles of one execution of instruction `mn ops`; `taken` is the share of executions that branched."""
    m = mn.split('.')[0]
    regs = lambda: len(re.findall(r'\b(r\d+|lr|pc|sp|r\d+-r\d+)\b', ops.split('{')[1])) if '{' in ops else 1
    if core == 'm4':
        p = 2
        if m in ('b', 'bl', 'blx', 'bx') or (m.startswith('b') and len(m) <= 3 and m not in ('bic', 'bfi', 'bfc')) or m in ('cbz', 'cbnz'):
            uncond = m in ('b', 'bl', 'blx', 'bx')
            return 1 + p if uncond else 1 + p * taken
        if m in ('sdiv', 'udiv'):
            return 12
        if m.startswith('ldm') or m.startswith('stm') or m in ('push', 'pop'):
            return 1 + regs() + (p if m == 'pop' and 'pc' in ops else 0)
        if m.startswith('ldr') or m.startswith('vldr'):
            return 2
        if m in ('vdiv', 'vsqrt'):
            return 14
        if m in ('vmla', 'vmls', 'vfma', 'vfms', 'vnmla', 'vnmls'):
            return 3
        if m.startswith('vpush') or m.startswith('vpop') or m.startswith('vldm') or m.startswith('vstm'):
            return 1 + regs()
        return 1
    # Cortex-M0+
    if m == 'bl':
        return 3
    if m in ('bx', 'blx'):
        return 2
    if m == 'b':
        return 2
    if m.startswith('b') and len(m) <= 3 and m not in ('bic', 'bics'):
        return 1 + taken
    if m.startswith('ldm') or m.startswith('stm') or m in ('push', 'pop'):
        return 1 + regs() + (2 if m == 'pop' and 'pc' in ops else 0)
    if m.startswith('ldr') or m.startswith('str'):
        return 2
    return 1


def measure(only):
    """Builds the board (one strategy; one scene, or all where `only` is None), runs it with the plugin: its `bench`
    lines' fields and the cycles per instruction of its draw code."""
    env = dict(os.environ, CARGO_TARGET_DIR='/tmp/wraster-cycles')
    env.pop('ONLY', None)
    env.pop('RECIP', None)
    if only:
        env['ONLY'] = only
    if recip:
        env['RECIP'] = recip
    subprocess.run(['cargo', 'build', '--release', '--quiet', '--features', 'size-probe'],
                   cwd=os.path.join(boards, board), env=env, check=True)
    elf = f'/tmp/wraster-cycles/{target}/release/wraster-{board}'
    counts = f'/tmp/wraster-cycles-{board}-{only or "all"}-{recip or "default"}.txt'
    out = subprocess.run(qemu + ['-nographic', '-icount', 'shift=0', '-semihosting-config', 'enable=on,target=native',
                                 '-kernel', elf, '-plugin', f'{plugin},out={counts}'],
                         capture_output=True, text=True, check=True).stdout
    benches = [dict(kv.split('=', 1) for kv in l.split()[1:]) for l in out.splitlines() if l.startswith('bench ')]
    dis, func, path = {}, {}, {}
    for a, text, f_, p, _ in disassemble(elf):
        parts = text.split('@')[0].split(None, 1)
        if parts:
            dis[a], func[a], path[a] = (parts[0], parts[1] if len(parts) > 1 else ''), f_, p
    cnt = {}
    for line in open(counts):
        a, c = line.split()
        cnt[int(a, 16)] = int(c)
    addrs = sorted(dis)
    nxt = {a: b for a, b in zip(addrs, addrs[1:])}
    skip_fn = re.compile(r'__stext|memset|memclr|memcpy|fmt|Formatter|heapless|semihosting|hprint|Reset|__pre_init')
    ins = cyc = 0
    for a, c in cnt.items():
        if a not in dis or skip_fn.search(func[a]) or '/boards/' in path[a]:
            continue
        mn, ops = dis[a]
        fall = cnt.get(nxt.get(a), 0)
        taken = max(0.0, min(1.0, (c - fall) / c)) if c else 0.0
        ins += c
        cyc += c * cycles_of(mn, ops, taken)
    return benches, cyc / ins


if together:
    benches, cpi = measure(None)
    n = sum(int(f['instructions']) for f in benches)
    px = sum(int(f['pixels']) for f in benches)
    names = {f['recip'] for f in benches}
    print(f"cycles board={board} recip={'/'.join(sorted(names))} scenes={len(benches)} instructions={n} pixels={px} "
          f"instr_per_px={n / px:.1f} cpi={cpi:.3f} est_cycles_per_px={n * cpi / px:.1f}", flush=True)
    sys.exit(0)

for scene in scenes:
    benches, cpi = measure(scene)
    f = benches[0]
    n = int(f['instructions'])
    px, fr, tri = int(f['pixels']), int(f['fragments']), int(f['triangles'])
    print(f"cycles board={board} scene={scene} instructions={n} instr_per_px={n / px:.1f} instr_per_fragment={n / fr:.1f} "
          f"instr_per_tri={n / tri:.1f} cpi={cpi:.3f} est_cycles_per_px={n * cpi / px:.1f} "
          f"est_cycles_per_fragment={n * cpi / fr:.1f} est_cycles_per_tri={n * cpi / tri:.1f}", flush=True)
