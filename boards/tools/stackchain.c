/* stackchain: a QEMU TCG plugin for where a firmware's deepest stack goes. Like stackdepth.c it tracks the lowest
 * address any store writes in [lo, hi) (the stack's region), and at each new lowest store it copies the stack from
 * there to `hi` (qemu_plugin_read_memory_vaddr); at exit it prints the `stack ...` line with the storing PC and that
 * copy as `w ADDR VALUE` words. `stackchain.py` follows the frame pointers (r7 on thumbv6m: each frame holds the
 * caller's r7 and the return address) through the copy and names each frame's function and size.
 *
 * Build: cc -shared -fPIC -O2 -o stackchain.so stackchain.c
 * Use:   qemu-system-arm ... -plugin ./stackchain.so,lo=0x<__ebss>,hi=0x<_stack_start> -kernel ELF 2> out.txt
 *        python3 stackchain.py ELF out.txt
 * Debian ships no plugin header: the few declarations used are written out below (GByteArray's layout is GLib's).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdbool.h>
typedef uint64_t qemu_plugin_id_t;
typedef uint32_t qemu_plugin_meminfo_t;
struct qemu_plugin_tb; struct qemu_plugin_insn;
typedef struct { uint8_t *data; unsigned int len; } GByteArray;
extern GByteArray *g_byte_array_new(void);
typedef void (*tb_trans_cb)(qemu_plugin_id_t, struct qemu_plugin_tb *);
typedef void (*mem_cb)(unsigned int, qemu_plugin_meminfo_t, uint64_t, void *);
typedef void (*udata_cb)(qemu_plugin_id_t, void *);
extern void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t, tb_trans_cb);
extern size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
extern struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
extern uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
extern void qemu_plugin_register_vcpu_mem_cb(struct qemu_plugin_insn *, mem_cb, int flags, int rw, void *);
extern void qemu_plugin_register_atexit_cb(qemu_plugin_id_t, udata_cb, void *);
extern bool qemu_plugin_read_memory_vaddr(uint64_t addr, GByteArray *data, size_t len);
__attribute__((visibility("default"))) int qemu_plugin_version = 4; /* QEMU 10.0 */
static uint64_t lo, hi, lowest = UINT64_MAX, lowpc;
static GByteArray *snap; static uint8_t buf[65536]; static unsigned blen;
static void store(unsigned int vcpu, qemu_plugin_meminfo_t info, uint64_t addr, void *p) {
    if (addr >= lo && addr < hi && addr < lowest) {
        lowest = addr; lowpc = (uint64_t)(uintptr_t)p;
        snap->len = 0;
        if (qemu_plugin_read_memory_vaddr(addr, snap, hi - addr)) { blen = snap->len; memcpy(buf, snap->data, blen); }
    }
}
static void trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) { struct qemu_plugin_insn *in = qemu_plugin_tb_get_insn(tb, i);
        qemu_plugin_register_vcpu_mem_cb(in, store, 0, 2, (void *)(uintptr_t)qemu_plugin_insn_vaddr(in)); }
}
static void done(qemu_plugin_id_t id, void *p) {
    fprintf(stderr, "stack lowest=0x%llx used=%llu free=%llu pc=0x%llx\n", (unsigned long long)lowest, (unsigned long long)(hi-lowest), (unsigned long long)(lowest-lo), (unsigned long long)lowpc);
    for (unsigned i = 0; i + 4 <= blen; i += 4) { uint32_t w; memcpy(&w, buf + i, 4);
        fprintf(stderr, "w 0x%llx 0x%x\n", (unsigned long long)(lowest + i), w); }
}
__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const void *info, int argc, char **argv) {
    for (int i = 0; i < argc; i++) { if (!strncmp(argv[i], "lo=", 3)) lo = strtoull(argv[i]+3, NULL, 0);
        if (!strncmp(argv[i], "hi=", 3)) hi = strtoull(argv[i]+3, NULL, 0); }
    snap = g_byte_array_new();
    qemu_plugin_register_vcpu_tb_trans_cb(id, trans); qemu_plugin_register_atexit_cb(id, done, NULL); return 0;
}
