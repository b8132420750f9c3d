#define _POSIX_C_SOURCE 200809L // NOLINT(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp): feature-test macro

#include "sim_hal/file_nvm.h"
#include "hal/hal_byte_order.h"
#include "sim_hal/path.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

uint32_t file_nvm_crc32(uint32_t crc, const uint8_t *p, size_t n)
{
    crc = ~crc;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int b = 0; b < 8; b++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

static const char *file_kind(mode_t mode)
{
    if (S_ISFIFO(mode)) {
        return "a FIFO";
    }
    if (S_ISDIR(mode)) {
        return "a directory";
    }
    if (S_ISCHR(mode)) {
        return "a character device";
    }
    if (S_ISBLK(mode)) {
        return "a block device";
    }
    if (S_ISSOCK(mode)) {
        return "a socket";
    }
    return "something else";
}

/* -1 with err when something other than a regular file is at path; 0 for a file or nothing. */
static int check_kind(const char *path, char *err, size_t errlen)
{
    struct stat st;
    /* A stat error other than "nothing there" is left to the open, which reports it. */
    if (stat(path, &st) != 0 || S_ISREG(st.st_mode)) {
        return 0;
    }
    snprintf(err, errlen, "%s: %s, not a regular file", path, file_kind(st.st_mode));
    return -1;
}

/* Every write creates PATH.tmp and renames it in path's directory: without one that can be
 * written there, each non-volatile write would fail long after the start. */
static int check_dir(const char *path, char *err, size_t errlen)
{
    char dir[FILE_NVM_PATH_MAX + 8];
    (void)sim_path_split(path, dir, sizeof dir);
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(err, errlen, "%s: the directory %s does not exist", path, dir);
        return -1;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        snprintf(err, errlen, "%s: the directory %s is not writable (%s)", path, dir,
                 strerror(errno));
        return -1;
    }
    return 0;
}

/* The pid the holder of the lock on fd wrote into it, or 0. */
static long lock_holder(int fd)
{
    char buf[24];
    ssize_t n = pread(fd, buf, sizeof buf - 1u, 0);
    if (n <= 0) {
        return 0;
    }
    buf[n] = '\0';
    char *end = NULL;
    long pid = strtol(buf, &end, 10);
    return end != buf && pid > 0 ? pid : 0;
}

static void in_use_text(const char *path, int fd, char *err, size_t errlen)
{
    long pid = lock_holder(fd);
    char who[40] = "";
    if (pid > 0) {
        snprintf(who, sizeof who, "pid %ld, ", pid);
    }
    snprintf(err, errlen, "%s: in use by another process (%slock %s.lock)", path, who, path);
}

/* -1 with "PATH: PATH.SUFFIX is a symbolic link ..." when one is at PATH.SUFFIX. We make
 * PATH.lock and PATH.tmp as files: a link there was put by someone else, and following it would
 * make us write its target. PATH itself is only renamed over, but a link there would be read
 * and then silently replaced: refused as well (SUFFIX ""). */
static int check_no_link(const char *path, const char *suffix, char *err, size_t errlen)
{
    char name[FILE_NVM_PATH_MAX + 8];
    snprintf(name, sizeof name, "%s%s", path, suffix);
    struct stat st;
    if (lstat(name, &st) == 0 && S_ISLNK(st.st_mode)) {
        /* The caller adds ": refused" (file_nvm_check_path) or says the file is not used. */
        snprintf(err, errlen, "%s: %s is a symbolic link (dfp-sim writes no file through a link)",
                 path, name);
        return -1;
    }
    return 0;
}

/* Whether another process holds path's lock, without creating the lock file. */
static int check_lock(const char *path, char *err, size_t errlen)
{
    char lock[FILE_NVM_PATH_MAX + 8];
    snprintf(lock, sizeof lock, "%s.lock", path);
    int fd = open(lock, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW);
    if (fd < 0) {
        /* No lock file: nobody has opened path yet. A link there: check_no_link said so. */
        return 0;
    }
    /* Shared: two processes checking at once do not see each other as the holder. */
    int rc = 0;
    if (flock(fd, LOCK_SH | LOCK_NB) != 0) {
        in_use_text(path, fd, err, errlen);
        rc = -1;
    }
    close(fd); /* also gives up the shared lock */
    return rc;
}

int file_nvm_check_path(const char *path, char *err, size_t errlen)
{
    char dummy[1];
    if (err == NULL || errlen == 0u) {
        err = dummy;
        errlen = sizeof dummy;
    }
    if (path == NULL) {
        return 0;
    }
    if (check_kind(path, err, errlen) != 0) {
        return FILE_NVM_NOT_FILE;
    }
    if (check_dir(path, err, errlen) != 0 || check_no_link(path, "", err, errlen) != 0 ||
        check_no_link(path, ".lock", err, errlen) != 0 ||
        check_no_link(path, ".tmp", err, errlen) != 0 || check_lock(path, err, errlen) != 0) {
        return FILE_NVM_UNUSABLE;
    }
    return 0;
}

enum {
    LOAD_OK = 0,
    LOAD_MISSING = -1,   /* ENOENT; err says "no such file" */
    LOAD_DAMAGED = -2,   /* err says why */
    LOAD_NOT_FILE = -3,  /* not a regular file; err says what it is */
};

/* The open cannot block: stat first, O_NONBLOCK for a FIFO put there after the stat. */
static int open_regular(const char *path, char *err, size_t errlen)
{
    if (check_kind(path, err, errlen) != 0) {
        return LOAD_NOT_FILE;
    }
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        if (errno == ENOENT) {
            snprintf(err, errlen, "%s: no such file", path);
            return LOAD_MISSING;
        }
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return LOAD_DAMAGED;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(err, errlen, "%s: cannot stat: %s", path, strerror(errno));
        close(fd);
        return LOAD_DAMAGED;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "%s: %s, not a regular file", path, file_kind(st.st_mode));
        close(fd);
        return LOAD_NOT_FILE;
    }
    return fd;
}

/* The whole file into f->image: its length, or -1 with err. */
static long read_whole(file_nvm_t *f, int fd, const char *path, char *err, size_t errlen)
{
    size_t got = 0;
    for (;;) {
        ssize_t r = read(fd, f->image + got, sizeof f->image - got);
        if (r < 0) {
            if (errno == EINTR) {
                continue;
            }
            snprintf(err, errlen, "%s: read error: %s", path, strerror(errno));
            return -1;
        }
        got += (size_t)r;
        if (r == 0 || got == sizeof f->image) {
            return (long)got;
        }
    }
}

/* LOAD_OK: loaded into f->data; otherwise why in err (always naming path). */
static int load_image(file_nvm_t *f, const char *path, char *err, size_t errlen)
{
    int fd = open_regular(path, err, errlen);
    if (fd < 0) {
        return fd;
    }
    long n = read_whole(f, fd, path, err, errlen);
    close(fd);
    if (n < 0) {
        return LOAD_DAMAGED;
    }
    size_t got = (size_t)n;
    const uint8_t *h = f->image;
    if (got < FILE_NVM_HEADER) {
        /* No ';' in a reason: callers join texts with "; " and may split there. */
        snprintf(err, errlen, "%s: file too short (%zu bytes, less than the %u-byte header)", path,
                 got, (unsigned)FILE_NVM_HEADER);
        return LOAD_DAMAGED;
    }
    uint32_t magic = hal_get_be32(h);
    if (magic != FILE_NVM_MAGIC) {
        snprintf(err, errlen, "%s: not an EEPROM image (magic 0x%08X, expected 0x%08X)", path,
                 (unsigned)magic, (unsigned)FILE_NVM_MAGIC);
        return LOAD_DAMAGED;
    }
    uint32_t version = hal_get_be16(h + 4);
    uint32_t hlen = hal_get_be16(h + 6);
    uint32_t len = hal_get_be32(h + 8);
    if (version != FILE_NVM_VERSION || hlen != FILE_NVM_HEADER) {
        snprintf(err, errlen, "%s: image version %u / header length %u not supported", path,
                 (unsigned)version, (unsigned)hlen);
        return LOAD_DAMAGED;
    }
    if (len > FILE_NVM_MAX_SIZE || got != FILE_NVM_HEADER + len) {
        snprintf(err, errlen,
                 "%s: length field says %u data bytes but the file holds %zu (truncated or "
                 "appended to)",
                 path, (unsigned)len, got - FILE_NVM_HEADER);
        return LOAD_DAMAGED;
    }
    uint32_t stored = hal_get_be32(h + 16);
    uint32_t crc = file_nvm_crc32(0, h, 16);
    crc = file_nvm_crc32(crc, h + FILE_NVM_HEADER, len);
    if (crc != stored) {
        snprintf(err, errlen, "%s: CRC mismatch (stored 0x%08X, computed 0x%08X): contents damaged",
                 path, (unsigned)stored, (unsigned)crc);
        return LOAD_DAMAGED;
    }
    memset(f->data, 0xFF, f->size);
    memcpy(f->data, h + FILE_NVM_HEADER, len < f->size ? len : f->size);
    f->seq = hal_get_be32(h + 12);
    return LOAD_OK;
}

/* PATH could not be used (rc): the previous generation, or a blank or no image. */
static int open_previous(file_nvm_t *f, int rc, const char *why, char *err, size_t errlen)
{
    char bak[FILE_NVM_PATH_MAX + 8];
    snprintf(bak, sizeof bak, "%s.bak", f->path);
    char bwhy[FILE_NVM_PATH_MAX + 160];
    bwhy[0] = '\0';
    int brc = load_image(f, bak, bwhy, sizeof bwhy);
    if (brc == LOAD_OK) {
        f->readable = true;
        f->loaded = FILE_NVM_IMAGE_BACKUP;
        /* PATH.bak is exactly one write older than PATH (nvm_write): that write is gone. */
        snprintf(err, errlen, "%s; using the previous image %s (the writes after it are lost)",
                 why, bak);
        return 1;
    }
    memset(f->data, 0xFF, f->size);
    if (rc == LOAD_MISSING && brc == LOAD_MISSING) {
        f->readable = true;
        f->loaded = FILE_NVM_IMAGE_BLANK; /* first start */
        return 0;
    }
    f->readable = false;
    f->loaded = FILE_NVM_IMAGE_NONE;
    snprintf(err, errlen, "%s; %s: no usable image", why, bwhy);
    return -1;
}

/* Marks f's own lock: its address mixed with a constant, which neither a blank or
 * uninitialised struct nor a copy of an open one is likely to carry. */
static uintptr_t file_nvm_lock_tag(const file_nvm_t *f)
{
    return (uintptr_t)f ^ (uintptr_t)0x4C4F434Bu;
}

void file_nvm_close(file_nvm_t *f)
{
    if (f != NULL && f->lock_tag == file_nvm_lock_tag(f)) {
        close(f->lock_fd);
        f->lock_tag = 0u;
    }
}

/* PATH.lock, flock'ed for the life of f: each process keeps its own copy of the image and every
 * write replaces the whole file, so a second user would undo the first one's acknowledged
 * writes. PATH itself cannot carry the lock, since every write renames a new file over it.
 * 0: f holds the lock; -1 with err: another process does; -2 with err: a link is there. */
static int take_lock(file_nvm_t *f, char *err, size_t errlen)
{
    char lock[FILE_NVM_PATH_MAX + 8];
    snprintf(lock, sizeof lock, "%s.lock", f->path);
    /* 0644: another user's dfp-sim must be able to open it to see it is held. */
    int fd = open(lock, O_RDWR | O_CREAT | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW, 0644);
    bool writable = fd >= 0;
    if (fd < 0 && errno != ELOOP) {
        fd = open(lock, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW); /* another user's */
    }
    if (fd < 0 && check_no_link(f->path, ".lock", err, errlen) != 0) {
        return -2;
    }
    if (fd < 0) {
        /* Where no lock file can be made, no PATH.tmp can either: every write fails, and two
         * users have no writes to lose. */
        return 0;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        in_use_text(f->path, fd, err, errlen);
        close(fd);
        return -1;
    }
    f->lock_fd = fd;
    f->lock_tag = file_nvm_lock_tag(f);
    if (writable) { /* the pid only serves the message of the next one who tries */
        char pid[24];
        int n = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
        ssize_t w = ftruncate(fd, 0) == 0 ? pwrite(fd, pid, (size_t)n, 0) : -1;
        (void)w;
    }
    return 0;
}

int file_nvm_open(file_nvm_t *f, const char *path, size_t size, char *err, size_t errlen)
{
    file_nvm_close(f); /* opened again: the old lock goes with the old image */
    char dummy[1];
    if (err == NULL || errlen == 0) {
        err = dummy;
        errlen = sizeof dummy;
    }
    err[0] = '\0';
    memset(f, 0, sizeof *f);
    f->sync = true;
    if (path == NULL || strlen(path) + 5 > sizeof f->path) {
        snprintf(err, errlen, "EEPROM path missing or too long");
        return -1;
    }
    if (size == 0 || size > FILE_NVM_MAX_SIZE) {
        snprintf(err, errlen, "EEPROM size %zu out of range (1..%u)", size,
                 (unsigned)FILE_NVM_MAX_SIZE);
        return -1;
    }
    memcpy(f->path, path, strlen(path) + 1);
    f->size = size;
    memset(f->data, 0xFF, size);

    char why[FILE_NVM_PATH_MAX + 160];
    why[0] = '\0';
    /* Locked before it is read, so the image read is the one the lock holder left. */
    int locked = check_kind(path, why, sizeof why) == 0 ? take_lock(f, why, sizeof why) : 0;
    if (locked == -1) {
        f->loaded = FILE_NVM_IMAGE_IN_USE;
        snprintf(err, errlen, "%s", why);
        return -1;
    }
    if (locked == -2) {
        f->loaded = FILE_NVM_IMAGE_REFUSED;
        snprintf(err, errlen, "%s: refused, nothing is read from or written to it", why);
        return -1;
    }
    int rc = load_image(f, path, why, sizeof why);
    if (rc == LOAD_OK) {
        f->readable = true;
        f->main_valid = true;
        f->loaded = FILE_NVM_IMAGE_MAIN;
        return 0;
    }
    if (rc == LOAD_NOT_FILE) {
        /* Not an image that went bad but a wrong path: no backup would be the user's data. */
        f->loaded = FILE_NVM_IMAGE_REFUSED;
        snprintf(err, errlen, "%s: refused, nothing is read from or written to it", why);
        return -1;
    }
    return open_previous(f, rc, why, err, errlen);
}

static size_t nvm_size(void *ctx)
{
    const file_nvm_t *f = ctx;
    return f->size;
}

static int nvm_read(void *ctx, size_t offset, uint8_t *data, size_t len)
{
    const file_nvm_t *f = ctx;
    if (!f->readable || offset > f->size || len > f->size - offset) {
        return -1;
    }
    memcpy(data, f->data + offset, len);
    return 0;
}

static int write_all(int fd, const uint8_t *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR) {
                continue;
            }
            return -1;
        }
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

static int sync_dir(const char *path)
{
    char dir[FILE_NVM_PATH_MAX];
    (void)sim_path_split(path, dir, sizeof dir);
    int fd = open(dir, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        return -1;
    }
    int rc = fsync(fd);
    close(fd);
    return rc;
}

/* tmp created anew with O_EXCL, so nothing is ever written through a link. A file left there by
 * a crash, or a link someone put there, is unlinked first (which removes a link, not its
 * target); anything else there (a FIFO, a directory) is left alone and the write fails.
 * 0644, the image's mode, since tmp becomes the image. */
static int create_tmp(const char *tmp)
{
    const int flags = O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK;
    int fd = open(tmp, flags, 0644);
    struct stat st;
    if (fd < 0 && errno == EEXIST && lstat(tmp, &st) == 0 &&
        (S_ISREG(st.st_mode) || S_ISLNK(st.st_mode)) && unlink(tmp) == 0) {
        fd = open(tmp, flags, 0644);
    }
    return fd;
}

/* The new image into tmp, on the disk when sync: 0, or -1 with tmp removed. */
static int write_tmp(const char *tmp, const uint8_t *img, size_t n, bool sync)
{
    int fd = create_tmp(tmp);
    if (fd < 0) {
        return -1;
    }
    if (write_all(fd, img, n) != 0 || (sync && fsync(fd) != 0)) {
        close(fd);
        unlink(tmp);
        return -1;
    }
    if (close(fd) != 0) {
        unlink(tmp);
        return -1;
    }
    return 0;
}

static int nvm_write(void *ctx, size_t offset, const uint8_t *data, size_t len)
{
    file_nvm_t *f = ctx;
    if (f->loaded == FILE_NVM_IMAGE_REFUSED || f->loaded == FILE_NVM_IMAGE_IN_USE ||
        offset > f->size || len > f->size - offset) {
        return -1;
    }
    uint8_t *img = f->image;
    uint8_t *payload = img + FILE_NVM_HEADER;
    if (f->readable) {
        memcpy(payload, f->data, f->size);
    } else {
        memset(payload, 0xFF, f->size); /* the old image was unusable: start blank */
    }
    memcpy(payload + offset, data, len);
    uint32_t seq = f->seq + 1u;
    hal_put_be32(img, FILE_NVM_MAGIC);
    hal_put_be16(img + 4, FILE_NVM_VERSION);
    hal_put_be16(img + 6, FILE_NVM_HEADER);
    hal_put_be32(img + 8, (uint32_t)f->size);
    hal_put_be32(img + 12, seq);
    uint32_t crc = file_nvm_crc32(0, img, 16);
    hal_put_be32(img + 16, file_nvm_crc32(crc, payload, f->size));

    char tmp[FILE_NVM_PATH_MAX + 8];
    char bak[FILE_NVM_PATH_MAX + 8];
    snprintf(tmp, sizeof tmp, "%s.tmp", f->path);
    snprintf(bak, sizeof bak, "%s.bak", f->path);
    if (write_tmp(tmp, img, FILE_NVM_HEADER + f->size, f->sync) != 0) {
        return -1;
    }
    if (f->main_valid) {
        /* Keep the current generation. Without hard links there is simply no backup. */
        if (unlink(bak) == 0 || errno == ENOENT) {
            (void)link(f->path, bak);
        }
    }
    if (rename(tmp, f->path) != 0) {
        unlink(tmp);
        return -1;
    }
    if (f->sync) {
        (void)sync_dir(f->path);
    }
    memcpy(f->data, payload, f->size);
    f->seq = seq;
    f->readable = true;
    f->main_valid = true;
    f->writes++;
    return 0;
}

static const hal_nvm_ops_t file_nvm_ops = {
    .size = nvm_size,
    .read = nvm_read,
    .write = nvm_write,
};

hal_nvm_t file_nvm_hal(file_nvm_t *f)
{
    return (hal_nvm_t){.ops = &file_nvm_ops, .ctx = f};
}
