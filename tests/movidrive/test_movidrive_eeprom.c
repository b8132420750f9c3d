/* Emulated MOVIDRIVE EEPROM: write vs write volatile across restarts, crash safety of the file
 * backend (truncated files, torn temporary files, a writer killed at random moments), corrupt
 * images (message + factory defaults, never a crash), factory setting, fault memory; what the
 * open says about the image it took, and paths that are not regular files (never blocking). */
#define _GNU_SOURCE

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "movidrive_test_util.h"
#include "sim_hal/file_nvm.h"

#define EE_SIZE 8192u

static char dir[512];
static char path[600];
static file_nvm_t nvm;
static movidrive_t md;
static char err[512];

static int open_md(int *nvm_rc)
{
    char nerr[512];
    int rc = file_nvm_open(&nvm, path, EE_SIZE, nerr, sizeof nerr);
    if (nvm_rc != NULL) {
        *nvm_rc = rc;
    }
    snprintf(err, sizeof err, "%s", nerr);
    movidrive_cfg_t cfg = {.eeprom = file_nvm_hal(&nvm), .terminal_enable = true};
    char merr[256];
    int mrc = movidrive_init(&md, &cfg, merr, sizeof merr);
    if (mrc != 0) {
        snprintf(err + strlen(err), sizeof err - strlen(err), "%s%s", err[0] ? " | " : "", merr);
    }
    return mrc;
}

static void use_file(const char *name)
{
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char p[700];
    unlink(path);
    snprintf(p, sizeof p, "%s.bak", path);
    unlink(p);
    snprintf(p, sizeof p, "%s.tmp", path);
    unlink(p);
}

static long read_file(const char *p, uint8_t *buf, size_t max)
{
    int fd = open(p, O_RDONLY);
    if (fd < 0) {
        return -1;
    }
    long n = (long)read(fd, buf, max);
    close(fd);
    return n;
}

static void write_file(const char *p, const uint8_t *buf, size_t n)
{
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        perror(p);
        return;
    }
    if (write(fd, buf, n) != (ssize_t)n) {
        perror(p);
    }
    close(fd);
}

static void test_blank_start(void)
{
    use_file("blank.ee");
    int nrc;
    CHECK_EQ(open_md(&nrc), 0);
    CHECK_EQ(nrc, 0);
    CHECK_STR(err, "");
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
    CHECK_EQ(movidrive_eeprom_size() <= EE_SIZE, 1);
    /* nothing is written until something is stored */
    struct stat st;
    CHECK_EQ(stat(path, &st), -1);
}

static void test_volatile_vs_non_volatile(void)
{
    use_file("persist.ee");
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 7000, 1), 0); /* write */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN, 5000, 0), 0); /* write volatile */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0 + 5, 1234, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0 + 6, 99, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P160_N11, (uint32_t)-300000, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P160_N11, 600000, 0), 0); /* volatile on top */
    CHECK_EQ(movidrive_write(&md, 8502, 3999999999u, 1), 0); /* unsigned */
    CHECK_EQ(movidrive_write(&md, 8617, 1, 1), 0); /* P840: not stored */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN), 5000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P160_N11), 600000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 6), 99);
    uint32_t writes = md.eeprom_writes;
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN, 4000, 0), 0);
    CHECK_EQ(md.eeprom_writes, writes); /* write volatile never touches the EEPROM */

    /* power cycle: same file */
    CHECK_EQ(open_md(NULL), 0);
    CHECK_STR(err, "");
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 7000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN), 2000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 5), 1234);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 6), 0);
    CHECK_EQ((int32_t)movidrive_read(&md, MOVIDRIVE_IDX_P160_N11), -300000);
    CHECK_EQ(movidrive_read(&md, 8502), 3999999999u);
    CHECK(md.ee_layout_ok);
    /* and once more after further writes */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 8000, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0 + 511, 0x80000000u, 1), 0);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 8000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 511), 0x80000000u);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 5), 1234);
}

/* Two generations: the file holds `new_value`, PATH.bak `old_value` of H0. */
static void two_generations(const char *name, int32_t old_value, int32_t new_value)
{
    use_file(name);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0, (uint32_t)old_value, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0, (uint32_t)new_value, 1), 0);
}

static void test_truncated_main(void)
{
    two_generations("trunc.ee", 111, 222);
    static uint8_t good[FILE_NVM_HEADER + EE_SIZE + 16];
    long n = read_file(path, good, sizeof good);
    CHECK_EQ(n, FILE_NVM_HEADER + EE_SIZE);
    const long lengths[] = {0, 1, 7, 19, 20, 21, 100, 4000, (long)FILE_NVM_HEADER + EE_SIZE - 1};
    for (size_t i = 0; i < sizeof lengths / sizeof lengths[0]; i++) {
        write_file(path, good, (size_t)lengths[i]);
        int nrc;
        CHECK_EQ(open_md(&nrc), 0);
        CHECK_EQ(nrc, 1); /* previous generation */
        CHECK(strstr(err, ".bak") != NULL);
        CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 111); /* exactly the old value */
    }
    printf("truncated image: \"%s\"\n", err);
    /* the next write replaces the damaged file and keeps the good backup */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0, 333, 1), 0);
    int nrc;
    CHECK_EQ(open_md(&nrc), 0);
    CHECK_EQ(nrc, 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 333);
    /* file intact again: the new value */
    write_file(path, good, (size_t)n);
    CHECK_EQ(open_md(&nrc), 0);
    CHECK_EQ(nrc, 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 222);
}

/* A crash while the temporary file is being written leaves PATH.tmp cut anywhere: ignored. */
static void test_torn_temporary(void)
{
    two_generations("tmp.ee", 5, 6);
    static uint8_t img[FILE_NVM_HEADER + EE_SIZE];
    long n = read_file(path, img, sizeof img);
    CHECK_EQ(n, (long)sizeof img);
    char tmp[700];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    const long lengths[] = {0, 3, 20, 500, (long)sizeof img - 1, (long)sizeof img};
    for (size_t i = 0; i < sizeof lengths / sizeof lengths[0]; i++) {
        img[FILE_NVM_HEADER + 100] ^= 0x5Au; /* some other content */
        write_file(tmp, img, (size_t)lengths[i]);
        int nrc;
        CHECK_EQ(open_md(&nrc), 0);
        CHECK_EQ(nrc, 0);
        CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 6);
    }
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0, 7, 1), 0);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 7);
    struct stat st;
    CHECK_EQ(stat(tmp, &st), -1); /* consumed by the rename */
}

static void test_damaged_bytes(void)
{
    two_generations("flip.ee", 41, 42);
    static uint8_t img[FILE_NVM_HEADER + EE_SIZE];
    long n = read_file(path, img, sizeof img);
    /* a flipped bit anywhere: CRC mismatch, previous generation */
    const size_t at[] = {0, 5, 12, 16, 19, 20, 21, 300, sizeof img - 1};
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        img[at[i]] ^= 0x10u;
        write_file(path, img, (size_t)n);
        img[at[i]] ^= 0x10u;
        int nrc;
        CHECK_EQ(open_md(&nrc), 0);
        CHECK_EQ(nrc, 1);
        CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 41);
    }
    img[300] ^= 1u;
    write_file(path, img, (size_t)n);
    open_md(NULL);
    printf("flipped bit: \"%s\"\n", err);
    CHECK(strstr(err, "CRC mismatch") != NULL);
    /* a file with bytes appended */
    static uint8_t longer[FILE_NVM_HEADER + EE_SIZE + 3];
    img[300] ^= 1u;
    memcpy(longer, img, sizeof img);
    write_file(path, longer, sizeof longer);
    int nrc;
    open_md(&nrc);
    CHECK_EQ(nrc, 1);
    CHECK(strstr(err, "length field") != NULL);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 41);
}

/* No usable image at all: a clear message, factory defaults, no crash; the next write heals. */
static void test_corrupt_without_backup(void)
{
    static uint8_t junk[9000];
    srand(7);
    for (size_t i = 0; i < sizeof junk; i++) {
        junk[i] = (uint8_t)rand();
    }
    const size_t sizes[] = {0, 1, 5, 19, 20, 64, 8212, sizeof junk};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        use_file("garbage.ee");
        write_file(path, junk, sizes[i]);
        int nrc;
        CHECK_EQ(open_md(&nrc), -1);
        CHECK_EQ(nrc, -1);
        CHECK(strstr(err, path) != NULL);
        CHECK(strstr(err, "factory defaults used") != NULL);
        CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
        CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P870_PO1), 9);
        CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 0);
        if (i == 2 || i == 6) {
            printf("garbage (%zu bytes): \"%s\"\n", sizes[i], err);
        }
    }
    CHECK(strstr(err, "not an EEPROM image") != NULL);
    use_file("short.ee");
    write_file(path, junk, 5);
    open_md(NULL);
    CHECK(strstr(err, "file too short") != NULL);
    /* a write replaces the garbage with a whole image */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 3000, 1), 0);
    int nrc;
    CHECK_EQ(open_md(&nrc), 0);
    CHECK_EQ(nrc, 0);
    CHECK_STR(err, "");
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 3000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN), 2000);
    /* a directory where the file should be */
    use_file("adir.ee");
    mkdir(path, 0755);
    CHECK_EQ(open_md(&nrc), -1);
    CHECK(strlen(err) > 0);
    printf("directory: \"%s\"\n", err);
    rmdir(path);
}

/* The file is fine but the bytes inside are not a MOVIDRIVE image, or hold bad values. */
static void test_bad_movidrive_image(void)
{
    use_file("inner.ee");
    char e[256];
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), 0);
    hal_nvm_t h = file_nvm_hal(&nvm);
    const uint8_t other[12] = {'X', 'Y', 'Z', 'W', 0, 1, 0, 0, 2, 0, 0, 0};
    CHECK_EQ(h.ops->write(h.ctx, 0, other, sizeof other), 0);
    CHECK_EQ(open_md(NULL), -1);
    CHECK(strstr(err, "no MOVIDRIVE image") != NULL);
    printf("foreign image: \"%s\"\n", err);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);

    /* a valid image, then one value out of range and one index the table does not know */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 3000, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN, 4000, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0 + 9, 9, 1), 0);
    CHECK(md.ee_layout_ok);
    uint8_t hdr[12];
    CHECK_EQ(h.ops->read(h.ctx, 0, hdr, 12), 0);
    CHECK_EQ(hal_get_be32(hdr), MOVIDRIVE_EE_MAGIC);
    /* find P130's record */
    size_t nrec = hal_get_be16(hdr + 6);
    int found = 0;
    for (size_t r = 0; r < nrec; r++) {
        uint8_t rec[6];
        h.ops->read(h.ctx, MOVIDRIVE_EE_HEADER + r * 6, rec, 6);
        uint16_t idx = hal_get_be16(rec);
        if (idx == MOVIDRIVE_IDX_P130_RAMP_UP) {
            const uint8_t bad[6] = {rec[0], rec[1], 0x7F, 0x00, 0x00, 0x00};
            h.ops->write(h.ctx, MOVIDRIVE_EE_HEADER + r * 6, bad, 6);
            found++;
        } else if (idx == 8302 - 1) {
            /* unreachable: 8301 is RO and not stored */
        }
    }
    CHECK_EQ(found, 1);
    CHECK_EQ(open_md(NULL), -1);
    CHECK(strstr(err, "1 stored values out of range") != NULL);
    printf("bad value: \"%s\"\n", err);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000); /* that one: default */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN), 4000); /* the rest: kept */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 9), 9);

    /* an image written by a table with a different layout: values found by index, and the next
     * write stores the whole image in this table's layout */
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), 0);
    h = file_nvm_hal(&nvm);
    static uint8_t img[EE_SIZE];
    memset(img, 0, sizeof img);
    const uint8_t hdr2[12] = {'M', 'D', 'E', 'E', 0, 1, 0, 2, 0x02, 0x00, 0, 0};
    memcpy(img, hdr2, 12);
    const uint8_t recs[12] = {0x21, 0x17, 0, 0, 0x1F, 0x40,  /* P131 = 8000 */
                              0x21, 0x16, 0, 0, 0x17, 0x70}; /* P130 = 6000 */
    memcpy(img + 12, recs, 12);
    img[12 + 12 + 3] = 42; /* H0 = 42 */
    CHECK_EQ(h.ops->write(h.ctx, 0, img, 12 + 12 + 2048), 0);
    CHECK_EQ(open_md(NULL), 0);
    CHECK(!md.ee_layout_ok);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 6000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P131_RAMP_DOWN), 8000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 42);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P160_N11, 1000, 1), 0);
    CHECK(md.ee_layout_ok);
    CHECK_EQ(open_md(NULL), 0);
    CHECK(md.ee_layout_ok);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 6000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P160_N11), 1000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 42);
}

static void test_factory_reset(void)
{
    use_file("factory.ee");
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 7000, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE, 3, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0 + 1, 5, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P803_PARAM_LOCK, 1, 1), 0);
    CHECK_EQ(movidrive_factory_reset(&md), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 1), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P803_PARAM_LOCK), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_FIRMWARE), 0x311C7289u);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0 + 1), 0);

    /* P802 = YES through the parameter channel (R: needs controller inhibit) */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 9000, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE, 3, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE, 2, 1), 0);
    movidrive_po3(&md, 0x0006, 0, 0); /* enabled: P802 refused */
    CHECK_EQ(movidrive_write(&md, 8594, 1, 1), ML_ADD_CONTROLLER_INHIBIT_REQUIRED);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 9000);
    movidrive_po3(&md, 0x0001, 0, 0); /* controller inhibit */
    CHECK_EQ(movidrive_write(&md, 8594, 0, 1), 0); /* NO: nothing happens */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 9000);
    CHECK_EQ(movidrive_write(&md, 8594, 1, 1), 0);
    CHECK_EQ(movidrive_read(&md, 8594), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE), 0);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE), 0);
    CHECK_EQ(movidrive_write(&md, 8594, 2, 1), ML_ADD_TOO_HIGH);
}

/* Fault memory P080..P084 (N/RO) survives a restart. */
static void test_fault_memory(void)
{
    use_file("faults.ee");
    CHECK_EQ(open_md(NULL), 0);
    const ml_fieldbus_status_t on = {.pd_config = 4, .pd_words = 3, .param_channel = true,
                                     .watchdog_ms = 100, .data_exchange = true};
    ml_fieldbus_status_t off = on;
    off.timeout = true;
    off.data_exchange = false;
    movidrive_fieldbus_status(&md, &off); /* P831 default 4: RAPID STOP/ERROR -> F28 */
    CHECK_EQ(md.fault, 28);
    movidrive_fieldbus_status(&md, &on);
    CHECK_EQ(movidrive_write(&md, 8617, 1, 0), 0); /* P840 manual reset */
    CHECK_EQ(md.fault, 0);
    movidrive_fieldbus_status(&md, &off);
    CHECK_EQ(movidrive_read(&md, 8366), 28); /* P080 error t-0 */
    CHECK_EQ(movidrive_read(&md, 8367), 28); /* P081 error t-1 */
    CHECK_EQ(movidrive_read(&md, 8368), 0);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_read(&md, 8366), 28);
    CHECK_EQ(movidrive_read(&md, 8367), 28);
    CHECK_EQ(md.fault, 0); /* a restart clears the fault itself */
    CHECK_EQ(movidrive_write(&md, 8596, 1, 0), 0); /* P804 = ERROR MEMORY */
    CHECK_EQ(movidrive_read(&md, 8366), 0);
    CHECK_EQ(open_md(NULL), 0);
    CHECK_EQ(movidrive_read(&md, 8367), 0);
}

/* NVM failures: too small, write error -> class 8 code 0x1F, RAM value kept. */
static int failing_write(void *ctx, size_t offset, const uint8_t *data, size_t len)
{
    (void)ctx;
    (void)offset;
    (void)data;
    (void)len;
    return -1;
}

static size_t big_size(void *ctx)
{
    (void)ctx;
    return EE_SIZE;
}

static size_t small_size(void *ctx)
{
    (void)ctx;
    return 100;
}

static int blank_read(void *ctx, size_t offset, uint8_t *data, size_t len)
{
    (void)ctx;
    (void)offset;
    memset(data, 0xFF, len);
    return 0;
}

static void test_nvm_failures(void)
{
    static const hal_nvm_ops_t bad_ops = {.size = big_size, .read = blank_read,
                                          .write = failing_write};
    static const hal_nvm_ops_t small_ops = {.size = small_size, .read = blank_read,
                                            .write = failing_write};
    movidrive_cfg_t cfg = {.eeprom = {.ops = &bad_ops, .ctx = NULL}, .terminal_enable = true};
    char e[256];
    CHECK_EQ(movidrive_init(&md, &cfg, e, sizeof e), 0);
    uint8_t rsp[8];
    movidrive_svc(&md, 0x32, MOVIDRIVE_IDX_P130_RAMP_UP, 3000, rsp);
    CHECK_BYTES(rsp, 8, 0xB2, 0x00, 0x21, 0x16, 0x08, 0x00, 0x00, 0x1F);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 3000);
    /* volatile: no EEPROM */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 2500, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_IPOS_H0, 1, 1), ML_ADD_NOT_SAVED);
    CHECK_EQ(movidrive_factory_reset(&md), -1);

    cfg.eeprom.ops = &small_ops;
    CHECK_EQ(movidrive_init(&md, &cfg, e, sizeof e), -1);
    printf("small EEPROM: \"%s\"\n", e);
    CHECK(strstr(e, "too small") != NULL);
    /* not stored, not an error */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 3000, 1), 0);

    /* no EEPROM at all */
    cfg.eeprom.ops = NULL;
    CHECK_EQ(movidrive_init(&md, &cfg, NULL, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 3000, 1), 0);
    CHECK_EQ(movidrive_factory_reset(&md), 0);
}

/* file_nvm on its own: sizes, ranges, reopen with another size. */
static void test_file_nvm(void)
{
    use_file("raw.ee");
    char e[256];
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    hal_nvm_t h = file_nvm_hal(&nvm);
    CHECK_EQ(h.ops->size(h.ctx), 64);
    uint8_t b[70];
    CHECK_EQ(h.ops->read(h.ctx, 0, b, 64), 0);
    CHECK_EQ(b[0], 0xFF);
    CHECK_EQ(h.ops->read(h.ctx, 60, b, 5), -1);
    CHECK_EQ(h.ops->write(h.ctx, 63, b, 2), -1);
    const uint8_t data[4] = {1, 2, 3, 4};
    CHECK_EQ(h.ops->write(h.ctx, 60, data, 4), 0);
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    CHECK_EQ(h.ops->read(h.ctx, 60, b, 4), 0);
    CHECK_BYTES(b, 4, 1, 2, 3, 4);
    CHECK_EQ(nvm.seq, 1);
    /* a larger size: padded with 0xFF; a smaller one: cut */
    CHECK_EQ(file_nvm_open(&nvm, path, 100, e, sizeof e), 0);
    CHECK_EQ(h.ops->read(h.ctx, 60, b, 6), 0);
    CHECK_BYTES(b, 6, 1, 2, 3, 4, 0xFF, 0xFF);
    CHECK_EQ(file_nvm_open(&nvm, path, 62, e, sizeof e), 0);
    CHECK_EQ(h.ops->read(h.ctx, 60, b, 2), 0);
    CHECK_BYTES(b, 2, 1, 2);
    CHECK_EQ(file_nvm_open(&nvm, path, 0, e, sizeof e), -1);
    CHECK_EQ(file_nvm_open(&nvm, path, FILE_NVM_MAX_SIZE + 1, e, sizeof e), -1);
    /* header layout: magic, version 1, header length 20, data length, sequence, CRC */
    uint8_t f[FILE_NVM_HEADER + 64];
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    CHECK_EQ(read_file(path, f, sizeof f), (long)sizeof f);
    CHECK_BYTES(f, 16, 'D', 'F', 'P', 'E', 0, 1, 0, 20, 0, 0, 0, 64, 0, 0, 0, 1);
    uint32_t crc = file_nvm_crc32(file_nvm_crc32(0, f, 16), f + 20, 64);
    CHECK_EQ(hal_get_be32(f + 16), crc);
    const uint8_t check[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    CHECK_EQ(file_nvm_crc32(0, check, 9), 0xCBF43926u);
    /* a write into a directory that vanished fails cleanly */
    char gone[700];
    snprintf(gone, sizeof gone, "%s/nodir/x.ee", dir);
    CHECK_EQ(file_nvm_open(&nvm, gone, 64, e, sizeof e), 0);
    CHECK_EQ(h.ops->write(h.ctx, 0, data, 4), -1);
    CHECK_EQ(h.ops->read(h.ctx, 0, b, 1), 0);
    CHECK_EQ(b[0], 0xFF); /* not changed */
}

/* Which image the open took and its exact words: a good file says nothing, a damaged one names
 * itself, its reason and the backup taken; with both unusable both files and reasons. */
static void test_open_reports(void)
{
    char e[2000];
    char want[2000];
    two_generations("report.ee", 10, 20);
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), 0);
    CHECK_STR(e, "");
    CHECK_EQ(nvm.loaded, FILE_NVM_IMAGE_MAIN);
    static uint8_t good[FILE_NVM_HEADER + EE_SIZE];
    CHECK_EQ(read_file(path, good, sizeof good), (long)sizeof good);
    write_file(path, good, 10);
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), 1);
    snprintf(want, sizeof want, "%s: file too short (10 bytes, less than the 20-byte header); "
             "using the previous image %s.bak (the writes after it are lost)", path, path);
    CHECK_STR(e, want);
    CHECK_EQ(nvm.loaded, FILE_NVM_IMAGE_BACKUP);
    CHECK_EQ(open_md(NULL), 0);
    /* the backup's value, not the lost 20 */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 10);
    /* both unusable */
    char bak[700];
    snprintf(bak, sizeof bak, "%s.bak", path);
    uint8_t junk[64];
    memset(junk, 'Z', sizeof junk);
    write_file(bak, junk, sizeof junk);
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), -1);
    snprintf(want, sizeof want, "%s: file too short (10 bytes, less than the 20-byte header); "
             "%s: not an EEPROM image (magic 0x5A5A5A5A, expected 0x44465045): no usable image",
             path, bak);
    CHECK_STR(e, want);
    CHECK_EQ(nvm.loaded, FILE_NVM_IMAGE_NONE);
    CHECK_EQ(open_md(NULL), -1);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0), 0); /* factory settings */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP), 2000);
    /* the file gone, the backup good */
    write_file(bak, good, sizeof good);
    unlink(path);
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), 1);
    snprintf(want, sizeof want, "%s: no such file; using the previous image %s (the writes after "
             "it are lost)", path, bak);
    CHECK_STR(e, want);
    use_file("report.ee");
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), 0);
    CHECK_STR(e, "");
    CHECK_EQ(nvm.loaded, FILE_NVM_IMAGE_BLANK);
}

/* A FIFO, a directory or a device is refused without being opened (a FIFO would block): SIGALRM
 * ends the test should anything block. A refused path is never written. */
static void test_not_regular(void)
{
    char e[2000];
    char want[2000];
    char side[700];
    alarm(10);
    use_file("fifo.ee");
    CHECK_EQ(file_nvm_check_path(path, e, sizeof e), 0); /* nothing there: created later */
    CHECK_EQ(mkfifo(path, 0644), 0);
    CHECK_EQ(file_nvm_check_path(path, e, sizeof e), -1);
    snprintf(want, sizeof want, "%s: a FIFO, not a regular file", path);
    CHECK_STR(e, want);
    CHECK_EQ(file_nvm_open(&nvm, path, EE_SIZE, e, sizeof e), -1);
    snprintf(want, sizeof want, "%s: a FIFO, not a regular file: refused, nothing is read from "
             "or written to it", path);
    CHECK_STR(e, want);
    CHECK_EQ(nvm.loaded, FILE_NVM_IMAGE_REFUSED);
    hal_nvm_t h = file_nvm_hal(&nvm);
    const uint8_t one[1] = {1};
    CHECK_EQ(h.ops->write(h.ctx, 0, one, 1), -1);
    struct stat st;
    CHECK(stat(path, &st) == 0 && S_ISFIFO(st.st_mode)); /* not renamed over */
    CHECK_EQ(file_nvm_check_path(dir, e, sizeof e), -1);
    snprintf(want, sizeof want, "%s: a directory, not a regular file", dir);
    CHECK_STR(e, want);
    CHECK_EQ(file_nvm_check_path("/dev/null", e, sizeof e), -1);
    CHECK_STR(e, "/dev/null: a character device, not a regular file");
    unlink(path);
    /* a FIFO as the backup, the file missing: reported, not opened; a write starts afresh */
    snprintf(side, sizeof side, "%s.bak", path);
    CHECK_EQ(mkfifo(side, 0644), 0);
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), -1);
    snprintf(want, sizeof want, "%s: no such file; %s: a FIFO, not a regular file: no usable "
             "image", path, side);
    CHECK_STR(e, want);
    CHECK_EQ(h.ops->write(h.ctx, 0, one, 1), 0);
    file_nvm_close(&nvm); /* else the check finds the file in use (by nvm) */
    CHECK_EQ(file_nvm_check_path(path, e, sizeof e), 0);
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    /* a FIFO left as the temporary file: the write fails, the image stays */
    snprintf(side, sizeof side, "%s.tmp", path);
    CHECK_EQ(mkfifo(side, 0644), 0);
    const uint8_t two[1] = {2};
    CHECK_EQ(h.ops->write(h.ctx, 0, two, 1), -1);
    unlink(side);
    uint8_t b[1];
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    CHECK_EQ(h.ops->read(h.ctx, 0, b, 1), 0);
    CHECK_EQ(b[0], 1);
    alarm(0);
}

/* A child writes H0 = 1, 2, 3, ... through the emulation as fast as it can; it is SIGKILLed at a
 * random moment, many times. After each kill the image must be exactly the last or the next
 * value, the file must open without complaint, and the child continues from there. */
typedef struct {
    volatile uint32_t started; /* the child began writing this value */
    volatile uint32_t done;    /* the write of this value returned */
    volatile uint32_t p130_started; /* the same for the second parameter, P130 */
    volatile uint32_t p130_done;
} progress_t;

/* The child: opens the image the last round left and writes H0 = value + 1, + 2, ... (and now
 * and then P130) until it is killed; reports its progress through pg. */
static void writer_child(progress_t *pg, uint32_t value) __attribute__((noreturn));
static void writer_child(progress_t *pg, uint32_t value)
{
    file_nvm_t cn;
    movidrive_t cm;
    char e[256];
    if (file_nvm_open(&cn, path, EE_SIZE, e, sizeof e) != 0) {
        _exit(3);
    }
    movidrive_cfg_t cfg = {.eeprom = file_nvm_hal(&cn), .terminal_enable = true};
    if (movidrive_init(&cm, &cfg, e, sizeof e) != 0) {
        _exit(4);
    }
    for (uint32_t v = value + 1;; v++) {
        pg->started = v;
        uint8_t req[8], rsp[8];
        movidrive_req(req, 0x32, MOVIDRIVE_IDX_IPOS_H0, v);
        movidrive_param(&cm, req, rsp);
        if (rsp[0] & 0x80) {
            _exit(5);
        }
        pg->done = v;
        if ((v & 7u) == 0) { /* now and then a second parameter */
            pg->p130_started = (v * 10u) % 2000000u;
            movidrive_req(req, 0x32, MOVIDRIVE_IDX_P130_RAMP_UP, pg->p130_started);
            movidrive_param(&cm, req, rsp);
            pg->p130_done = pg->p130_started;
        }
    }
}

typedef struct {
    int kills;
    int mid_write; /* kills between the start and the end of a write */
    int bad;
} kill_tally_t;

/* After a kill: the file opens without complaint, H0 and P130 are each the value last written
 * or the one being written. Returns H0, *p130 = P130. */
static uint32_t check_after_kill(int round, const progress_t *pg, uint32_t *p130,
                                 kill_tally_t *t)
{
    t->kills++;
    uint32_t started = pg->started;
    uint32_t done = pg->done;
    if (started != done) {
        t->mid_write++;
    }
    int nrc;
    int mrc = open_md(&nrc);
    CHECK_EQ(nrc, 0);
    CHECK_EQ(mrc, 0);
    uint32_t got = movidrive_read(&md, MOVIDRIVE_IDX_IPOS_H0);
    if (got != done && got != started) {
        t->bad++;
        fprintf(stderr, "round %d: H0 = %u, child had done %u, started %u\n", round,
                (unsigned)got, (unsigned)done, (unsigned)started);
    }
    *p130 = movidrive_read(&md, MOVIDRIVE_IDX_P130_RAMP_UP);
    if (*p130 != pg->p130_done && *p130 != pg->p130_started) {
        t->bad++;
        fprintf(stderr, "round %d: P130 = %u, child had done %u, started %u\n", round,
                (unsigned)*p130, (unsigned)pg->p130_done, (unsigned)pg->p130_started);
    }
    file_nvm_close(&nvm); /* the next writer's turn: one process at a time */
    return got;
}

static void test_kill_writer(void)
{
    use_file("kill.ee");
    progress_t *pg = mmap(NULL, sizeof *pg, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS,
                          -1, 0);
    CHECK(pg != MAP_FAILED);
    if (pg == MAP_FAILED) {
        return;
    }
    srand((unsigned)time(NULL));
    uint32_t value = 0;
    uint32_t p130 = 2000;
    kill_tally_t tally = {0, 0, 0};
    const int rounds = 60;
    for (int round = 0; round < rounds; round++) {
        pg->started = value;
        pg->done = value;
        pg->p130_started = p130;
        pg->p130_done = p130;
        fflush(NULL);
        pid_t pid = fork();
        if (pid == 0) {
            writer_child(pg, value);
        }
        CHECK(pid > 0);
        if (pid <= 0) {
            break;
        }
        /* let it get going, then kill it anywhere */
        for (int spin = 0; spin < 2000 && pg->started == value; spin++) {
            usleep(100);
        }
        usleep((useconds_t)(rand() % 4000));
        kill(pid, SIGKILL);
        int status = 0;
        waitpid(pid, &status, 0);
        if (!WIFSIGNALED(status)) {
            tally.bad++;
            fprintf(stderr, "child exited with %d\n", WEXITSTATUS(status));
            continue;
        }
        value = check_after_kill(round, pg, &p130, &tally);
    }
    CHECK_EQ(tally.bad, 0);
    CHECK_EQ(tally.kills, rounds);
    CHECK(value > 0); /* the writer made progress */
    printf("killed the writer %d times (%d between start and end of a write), H0 reached %u\n",
           tally.kills, tally.mid_write, (unsigned)value);
    munmap(pg, sizeof *pg);
}

static void remove_tree(const char *d)
{
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", d);
    if (system(cmd) != 0) {
        fprintf(stderr, "could not remove %s\n", d);
    }
}

int main(int argc, char **argv)
{
    snprintf(dir, sizeof dir, "%s/movidrive_eeprom_XXXXXX", argc > 1 ? argv[1] : "/tmp");
    if (mkdtemp(dir) == NULL) {
        perror(dir);
        return 1;
    }
    RUN_TEST(test_blank_start);
    RUN_TEST(test_volatile_vs_non_volatile);
    RUN_TEST(test_truncated_main);
    RUN_TEST(test_torn_temporary);
    RUN_TEST(test_damaged_bytes);
    RUN_TEST(test_corrupt_without_backup);
    RUN_TEST(test_bad_movidrive_image);
    RUN_TEST(test_factory_reset);
    RUN_TEST(test_fault_memory);
    RUN_TEST(test_nvm_failures);
    RUN_TEST(test_file_nvm);
    RUN_TEST(test_open_reports);
    RUN_TEST(test_not_regular);
    RUN_TEST(test_kill_writer);
    remove_tree(dir);
    return check_report();
}
