/* insncount: a QEMU TCG plugin counting executed guest instructions per PC, for instruction-level profiles of the
 * wraster firmware (QEMU is not cycle-accurate: these are instructions). Debian ships no plugin header, so the few
 * declarations of QEMU's plugin API used here are written out below.
 *
 * Build: cc -shared -DQEMU_PLUGIN_VERSION=4 -fPIC -O2 -o insncount.so insncount.c
 * Use:   qemu-system-arm ... -plugin ./insncount.so,out=profile.txt
 * Writes "pc count" lines (hex PC, decimal count) for every PC executed at least once.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
typedef void (*tb_trans_cb)(qemu_plugin_id_t, struct qemu_plugin_tb *);
typedef void (*vcpu_udata_cb)(unsigned int, void *);
typedef void (*udata_cb)(qemu_plugin_id_t, void *);

extern void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t, tb_trans_cb);
extern size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
extern struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
extern uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
extern void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *, vcpu_udata_cb, int flags, void *);
extern void qemu_plugin_register_atexit_cb(qemu_plugin_id_t, udata_cb, void *);

__attribute__((visibility("default"))) int qemu_plugin_version = QEMU_PLUGIN_VERSION; /* 4 for QEMU 10.0 */

#define SLOTS (1u << 22) /* PCs below 8 MiB (flash of every board here), half-word granular */
static uint64_t *counts;
static uint64_t base;
static const char *out = "insncount.txt";

static void exec(unsigned int vcpu, void *slot) { (void)vcpu; ++*(uint64_t *)slot; }

static void trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t k = (qemu_plugin_insn_vaddr(insn) - base) >> 1;
        if (k < SLOTS) qemu_plugin_register_vcpu_insn_exec_cb(insn, exec, 0, &counts[k]);
    }
}

static void done(qemu_plugin_id_t id, void *p) {
    (void)id; (void)p;
    FILE *f = fopen(out, "w");
    if (!f) return;
    for (uint64_t k = 0; k < SLOTS; k++)
        if (counts[k]) fprintf(f, "%llx %llu\n", (unsigned long long)(base + 2 * k), (unsigned long long)counts[k]);
    fclose(f);
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const void *info, int argc, char **argv) {
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (!strncmp(argv[i], "out=", 4)) out = argv[i] + 4;
        if (!strncmp(argv[i], "base=", 5)) base = strtoull(argv[i] + 5, NULL, 0);
    }
    counts = calloc(SLOTS, sizeof *counts);
    if (!counts) return -1;
    qemu_plugin_register_vcpu_tb_trans_cb(id, trans);
    qemu_plugin_register_atexit_cb(id, done, NULL);
    return 0;
}
