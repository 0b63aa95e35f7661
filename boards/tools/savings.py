#!/usr/bin/env python3
"""What a plan saves, measured: `python3 boards/tools/savings.py [--out FILE] [--scenes big,overdraw,...] [--cores m4,m0]`.

For each standard scene and W4 (the torus) and each core (the M4 and M0 QEMU boards), it runs the planner
(`cargo run --release -p host-tests --bin plan -- <scene> --core <core> --measure`: ranked by the
instructions each candidate costs on the board), then builds two firmwares and measures each:
- the plan's: `PLAN=<plan file> cargo run --release --features plan` (`plan,coarse` for a plan that keeps the coarse depth bound) in the board (only the plan's format, strategy
  and depth path; the depth buffer sized from the plan);
- the general default: the same board's default build of that scene alone (`ONLY=<scene> --features size-probe`, or
  `--features torus,size-probe`): W16, the core's default strategy, the scene's own depth range, the board's own
  buffers (the M4 a whole frame, the M0 15-row bands, 6 for the torus, with colour bands of half a byte a pixel).
Per firmware: the library's `.text` (`text_share.py`: instructions whose DWARF source is this repository's `src/`,
inlined code included), the whole `.text` and `.bss` (`llvm-size -A`), the depth RAM, the instructions per frame
(the board's `bench` line, counted around the draw calls: `instructions`, or `instr_per_frame` for the torus's 8
frames), and the visibility errors against the f64 reference (the planner's, for the plan and for the default).
Writes a Markdown table (default `report/savings.md`, which the report includes) and prints one line per row, last:
`savings scene=.. core=.. plan_format=.. plan_text=.. default_text=.. ...`.
"""
import glob, os, re, subprocess, sys

ROOT = os.path.realpath(os.path.join(os.path.dirname(__file__), '..', '..'))
BOARDS = {'m4': ('qemu-m4', 'thumbv7em-none-eabihf', 'wraster-qemu-m4'),
          'm0': ('qemu-m0', 'thumbv6m-none-eabi', 'wraster-qemu-m0')}
# The boards' own depth buffers (bytes): the M4's whole W16 frame; the M0's 15-row W16 bands (6 rows for the torus,
# whose 512 transformed vertices take most of its 16 KiB; its colour bands keep half a byte a pixel).
DEFAULT_DEPTH = {('m4', False): 320 * 240 * 2, ('m0', False): 320 * 15 * 2, ('m4', True): 320 * 240 * 2,
                 ('m0', True): 320 * 6 * 2}


def field(line, key):
    m = re.search(r'(?:^| )' + key + r'=(\S+)', line)
    return m.group(1) if m else None


def sh(cmd, cwd, env=None):
    e = dict(os.environ)
    e.update(env or {})
    r = subprocess.run(cmd, cwd=cwd, env=e, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)} in {cwd}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
    return r.stdout


def llvm_size(elf):
    tools = glob.glob(os.path.expanduser('~/.rustup/toolchains/*/lib/rustlib/*/bin/llvm-size'))
    out = sh([tools[0] if tools else 'llvm-size', '-A', elf], ROOT)
    sec = {}
    for line in out.splitlines():
        p = line.split()
        if len(p) >= 2 and p[0].startswith('.') and p[1].isdigit():
            sec[p[0]] = int(p[1])
    return sec


def measure(core, scene, env, features):
    board, target, binary = BOARDS[core]
    cwd = os.path.join(ROOT, 'boards', board)
    out = sh(['cargo', 'run', '--release', '--features', features], cwd, env)
    lines = [l for l in out.splitlines() if l.startswith('bench ') and field(l, 'scene') == scene]
    if len(lines) != 1:
        sys.exit(f'{board} {features} {env}: expected one bench line for {scene}, got:\n{out}')
    line = lines[0]
    per_frame = float(field(line, 'instr_per_frame') or field(line, 'instructions'))
    elf = os.path.join(ROOT, 'boards', 'target', target, 'release', binary)
    sec = llvm_size(elf)
    share = sh([sys.executable, os.path.join(ROOT, 'boards', 'tools', 'text_share.py'), elf], ROOT)
    lib = int(field(share.strip(), 'wraster'))
    return {'text': sec.get('.text', 0), 'bss': sec.get('.bss', 0), 'lib': lib, 'instr': per_frame,
            'hash': field(line, 'hash'), 'line': line}


def main():
    args = sys.argv[1:]
    out = os.path.join(ROOT, 'report', 'savings.md')
    scenes = ['big', 'overdraw', 'small', 'terrain', 'torus']
    cores = ['m4', 'm0']
    while args:
        a = args.pop(0)
        if a == '--out':
            out = args.pop(0)
        elif a == '--scenes':
            scenes = args.pop(0).split(',')
        elif a == '--cores':
            cores = args.pop(0).split(',')
        else:
            sys.exit(__doc__)
    commit = sh(['git', 'rev-parse', '--short', 'HEAD'], ROOT).strip()
    dirty = sh(['git', 'status', '--porcelain', '--untracked-files=no'], ROOT).strip()
    rows, lines = [], []
    for core in cores:
        for scene in scenes:
            plan_file = os.path.join(ROOT, 'target', 'plans', f'{scene}-{core}.rs')
            pout = sh(['cargo', 'run', '--release', '-q', '-p', 'host-tests', '--bin', 'plan', '--', scene,
                       '--core', core, '--out', plan_file, '--measure'], ROOT)
            pline = [l for l in pout.splitlines() if l.startswith('plan ')][-1]
            torus = scene == 'torus'
            feats = field(pline, 'features')
            # A plan that keeps the coarse depth bound is built with it (its firmware names the feature).
            p = measure(core, scene, {'PLAN': plan_file}, 'plan,coarse' if 'coarse' in feats.split(',') else 'plan')
            d = measure(core, scene, {} if torus else {'ONLY': scene}, 'torus,size-probe' if torus else 'size-probe')
            fmt = field(pline, 'format')
            r = dict(scene=scene, core=core, format=fmt, strategy=field(pline, 'strategy'), features=feats, plan=p,
                     default=d,
                     plan_depth=int(field(pline, 'depth_ram')), default_depth=DEFAULT_DEPTH[(core, torus)],
                     plan_err=int(field(pline, 'visibility_errors')),
                     default_err=int(field(pline, 'default_visibility_errors')),
                     budget_met=field(pline, 'budget_met'))
            rows.append(r)
            lines.append(
                f"savings scene={scene} core={core} plan_format={fmt} plan_strategy={r['strategy']} plan_features={feats} "
                f"plan_lib_text={p['lib']} default_lib_text={d['lib']} plan_text={p['text']} default_text={d['text']} "
                f"plan_bss={p['bss']} default_bss={d['bss']} plan_depth_ram={r['plan_depth']} "
                f"default_depth_ram={r['default_depth']} plan_instr_per_frame={p['instr']:.0f} "
                f"default_instr_per_frame={d['instr']:.0f} plan_visibility_errors={r['plan_err']} "
                f"default_visibility_errors={r['default_err']} budget_met={r['budget_met']}")
            print(lines[-1], flush=True)
    md = [f"Measured by `python3 boards/tools/savings.py` on commit {commit}{' (with local changes)' if dirty else ''}: "
          "each plan's firmware (`PLAN=<plan> cargo run --release --features plan`) against the board's default "
          "build of the same scene alone (W16, the core's default strategy, the scene's own range; `ONLY=<scene> "
          "--features size-probe`, `--features torus,size-probe` for W4). Library `.text`: the bytes whose source is "
          "wraster's `src/` (`text_share.py`, inlined code included). Instructions per frame: the board's count "
          "around the draw calls (QEMU instructions, not cycles). Visibility errors: pixels whose visible surface "
          "differs from the f64 reference's, over every frame.\n",
          "| scene | core | plan | library .text, plan / default | total .text, plan / default | .bss, plan / default "
          "| depth RAM, plan / default | instructions per frame, plan / default | visibility errors, plan / default |",
          "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        p, d = r['plan'], r['default']
        name = 'none' if r['format'] == 'none' else f"{r['format']} {r['strategy']}"
        if r['features'] != 'none':
            name += f" + {r['features']}"
        if r['budget_met'] != 'true':
            name += ' (budget not met)'
        md.append(f"| {r['scene']} | {r['core'].upper()} | {name} | {p['lib']:,} / {d['lib']:,} | "
                  f"{p['text']:,} / {d['text']:,} | {p['bss']:,} / {d['bss']:,} | {r['plan_depth']:,} / "
                  f"{r['default_depth']:,} | {p['instr']:,.0f} / {d['instr']:,.0f} | {r['plan_err']} / "
                  f"{r['default_err']} |")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    open(out, 'w').write('\n'.join(md) + '\n')
    print(f'wrote {out}')
    for l in lines:
        print(l)


if __name__ == '__main__':
    main()
