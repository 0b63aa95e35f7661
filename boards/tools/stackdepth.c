/* stackdepth: a QEMU TCG plugin measuring how deep a firmware's stack goes: the lowest address any store writes in
 * [lo, hi) (the RAM between the end of .bss, `__ebss`, and the initial stack pointer, `_stack_start`). A store at
 * `lo` itself means the stack reached the statics (on a Cortex-M0 without an MPU, an overflow writes over them
 * silently). The declarations of QEMU's plugin API used here are written out, as in insncount.c (GByteArray's
 * layout is GLib's, which QEMU links).
 *
 * Build: cc -shared -DQEMU_PLUGIN_VERSION=4 -fPIC -O2 -o stackdepth.so stackdepth.c
 * Use:   qemu-system-arm ... -plugin ./stackdepth.so,lo=0x20003010,hi=0x20004000[,words=1]
 * Prints "stack lo=0x.. hi=0x.. lowest=0x.. used=N free=M pc=0x.." to stderr at exit (used and free in bytes, pc
 * the lowest store's). With `words=1` it also copies the stack from each new lowest store up to `hi`
 * (qemu_plugin_read_memory_vaddr) and prints the copy as "w ADDR VALUE" lines: `stackchain.py` follows its frame
 * pointers to the functions whose frames make that depth.
 */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
typedef uint32_t qemu_plugin_meminfo_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
typedef struct { uint8_t *data; unsigned int len; } GByteArray;
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
extern GByteArray *g_byte_array_new(void);

__attribute__((visibility("default"))) int qemu_plugin_version = QEMU_PLUGIN_VERSION; /* 4 for QEMU 10.0 */

enum { CB_NO_REGS = 0, MEM_W = 2 };
static uint64_t lo, hi, lowest = UINT64_MAX, lowest_pc;
static int words;
static GByteArray *copy;
static uint8_t stack[1 << 16];
static unsigned stack_len;

static void store(unsigned int vcpu, qemu_plugin_meminfo_t info, uint64_t addr, void *pc) {
    (void)vcpu; (void)info;
    if (addr < lo || addr >= hi || addr >= lowest) return;
    lowest = addr;
    lowest_pc = (uint64_t)(uintptr_t)pc;
    if (words && hi - addr <= sizeof stack) {
        copy->len = 0;
        if (qemu_plugin_read_memory_vaddr(addr, copy, hi - addr)) {
            stack_len = copy->len;
            memcpy(stack, copy->data, stack_len);
        }
    }
}

static void trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        qemu_plugin_register_vcpu_mem_cb(insn, store, CB_NO_REGS, MEM_W,
                                         (void *)(uintptr_t)qemu_plugin_insn_vaddr(insn));
    }
}

static void done(qemu_plugin_id_t id, void *p) {
    (void)id; (void)p;
    uint64_t low = lowest == UINT64_MAX ? hi : lowest;
    fprintf(stderr, "stack lo=0x%llx hi=0x%llx lowest=0x%llx used=%llu free=%llu pc=0x%llx\n", (unsigned long long)lo,
            (unsigned long long)hi, (unsigned long long)low, (unsigned long long)(hi - low),
            (unsigned long long)(low - lo), (unsigned long long)lowest_pc);
    for (unsigned i = 0; i + 4 <= stack_len; i += 4) {
        uint32_t w;
        memcpy(&w, stack + i, 4);
        fprintf(stderr, "w 0x%llx 0x%x\n", (unsigned long long)(low + i), w);
    }
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const void *info, int argc, char **argv) {
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (!strncmp(argv[i], "lo=", 3)) lo = strtoull(argv[i] + 3, NULL, 0);
        if (!strncmp(argv[i], "hi=", 3)) hi = strtoull(argv[i] + 3, NULL, 0);
        if (!strncmp(argv[i], "words=", 6)) words = atoi(argv[i] + 6);
    }
    if (hi <= lo) return -1;
    if (words) copy = g_byte_array_new();
    qemu_plugin_register_vcpu_tb_trans_cb(id, trans);
    qemu_plugin_register_atexit_cb(id, done, NULL);
    return 0;
}
