"""The disassembly the board tools share (`profile.py`, `text_share.py`, `cycles.py`, `stackchain.py`): llvm-objdump's listing of an
ELF with its DWARF line info, one row per instruction."""
import glob, os, re, subprocess


def objdump():
    """The toolchain's llvm-objdump (`rustup component add llvm-tools`), else the one on PATH."""
    tools = glob.glob(os.path.expanduser('~/.rustup/toolchains/*/lib/rustlib/*/bin/llvm-objdump'))
    return tools[0] if tools else 'llvm-objdump'


def disassemble(elf, *args):
    """Yields `(address, text, function, path, line)` for every instruction of `elf` (`args` go to llvm-objdump, e.g.
    `-C`, `--section=.text`): `text` is the instruction as listed, `function` the symbol it is in, `path` and `line` the
    source line it came from (DWARF; inlined code counts for the line it came from), `'?'` and `''` before the first."""
    out = subprocess.run([objdump(), '-d', '-l', '--no-show-raw-insn', *args, elf], capture_output=True, text=True).stdout
    func, path, line = '?', '?', ''
    for row in out.splitlines():
        m = re.match(r'^[0-9a-f]+ <(.*)>:', row)
        if m:
            func, path, line = m.group(1), '?', ''
            continue
        m = re.match(r'^; (/\S+?):(\d+)', row)
        if m:
            path, line = m.group(1), m.group(2)
            continue
        m = re.match(r'\s*([0-9a-f]+):\s*(.*)', row)
        if m:
            yield int(m.group(1), 16), m.group(2), func, path, line
