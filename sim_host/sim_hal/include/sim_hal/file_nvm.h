/* hal_nvm_t on a file: the EEPROM of the emulated MOVIDRIVE (and anything else on the host that
 * needs non-volatile bytes).
 *
 * File = 20-byte header (magic "DFPE", version 1, header length, data length, sequence number,
 * CRC-32 over header and data, all big-endian) + data. Every write rewrites the whole image:
 * PATH.tmp is written and fsync'ed, the current PATH is hard-linked to PATH.bak (the previous
 * generation), PATH.tmp is renamed over PATH and the directory is fsync'ed. A crash at any
 * moment leaves PATH holding the old or the new image; should PATH itself be damaged
 * (truncated, overwritten), the previous generation in PATH.bak is used and the open says so.
 * PATH must be a regular file or not exist yet: anything else (a FIFO, a directory, a device)
 * is refused before it is opened, since opening a FIFO blocks and renaming over a device
 * would replace it.
 * One process at a time: the open takes an exclusive flock on PATH.lock (created beside PATH
 * and left there; it holds the holder's pid) until file_nvm_close or the end of the process,
 * and a second open of PATH, from another process or another file_nvm_t, is refused.
 * No symbolic link is followed where a file is written: one at PATH.lock is refused (it was not
 * made by us, and following it would write its target); PATH.tmp is created with O_EXCL after
 * unlinking whatever file or link is at that name; PATH is only replaced by rename. */
#ifndef SIM_HAL_FILE_NVM_H
#define SIM_HAL_FILE_NVM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_nvm.h"

#define FILE_NVM_MAX_SIZE 16384u
#define FILE_NVM_PATH_MAX 480u
#define FILE_NVM_HEADER 20u
#define FILE_NVM_MAGIC 0x44465045u /* "DFPE" */
#define FILE_NVM_VERSION 1u

/* Which image file_nvm_open took, for callers that tell the user more than err does. */
typedef enum file_nvm_image {
    FILE_NVM_IMAGE_NONE = 0, /* no usable image: reads fail until the next write */
    FILE_NVM_IMAGE_BLANK,    /* neither PATH nor PATH.bak exists: a blank EEPROM (first start) */
    FILE_NVM_IMAGE_MAIN,     /* PATH */
    FILE_NVM_IMAGE_BACKUP,   /* PATH.bak, the previous generation: PATH was damaged or missing */
    FILE_NVM_IMAGE_REFUSED,  /* PATH is not a regular file, or PATH.lock is a symbolic link:
                              * never read nor written */
    FILE_NVM_IMAGE_IN_USE,   /* another process holds PATH.lock: never read nor written */
} file_nvm_image_t;

typedef struct file_nvm {
    char path[FILE_NVM_PATH_MAX];
    file_nvm_image_t loaded; /* what file_nvm_open took; writes do not change it */
    size_t size;
    bool readable;   /* false: no usable image; reads fail until the next write */
    bool main_valid; /* PATH holds a valid image (kept as PATH.bak by the next write) */
    bool sync;       /* fsync file and directory on every write (default true) */
    uint32_t seq;    /* sequence number of the current image */
    uint32_t writes;
    /* The flock'ed PATH.lock; valid only while lock_tag is file_nvm_lock_tag(f), so that a struct
     * never opened (whatever its bytes) or a copy of an open one owns no descriptor. */
    int lock_fd;
    uintptr_t lock_tag;
    uint8_t data[FILE_NVM_MAX_SIZE];
    /* Scratch for a whole file image being read or written: header + data, and one byte more
     * so a too-long file is noticed. Here rather than shared, so images never meet. */
    uint8_t image[FILE_NVM_HEADER + FILE_NVM_MAX_SIZE + 1u];
} file_nvm_t;

/* Opens (does not create) the image at path with `size` data bytes (<= FILE_NVM_MAX_SIZE);
 * f->loaded says which image was taken. err names every file it speaks of:
 *  0  image loaded, or no file yet (all bytes 0xFF, a blank EEPROM); err empty;
 *  1  PATH damaged or missing, the previous generation PATH.bak was loaded:
 *     "PATH: <reason>; using the previous image PATH.bak (the writes after it are lost)";
 * -1  no usable image: "PATH: <reason>; PATH.bak: <reason>: no usable image" (reasons: corrupt,
 *     short, garbage, unreadable, "no such file"); reads fail until the next write, which starts
 *     from a blank image. Or PATH is not a regular file: "PATH: a FIFO, not a regular file:
 *     refused, nothing is read from or written to it", and every write fails. Or PATH is in
 *     use: "PATH: in use by another process (pid N, lock PATH.lock)", and every write fails.
 *     Or a symbolic link is at PATH.lock: "PATH: PATH.lock is a symbolic link (dfp-sim writes
 *     no file through a link): refused, nothing is read from or written to it" (f->loaded
 *     FILE_NVM_IMAGE_REFUSED), and every write fails.
 *     Or bad arguments. Opening f again first closes it (file_nvm_close).
 * No reason contains "; ", so callers may split err there. A shorter or longer image from
 * another size is accepted: cut or padded with 0xFF. */
int file_nvm_open(file_nvm_t *f, const char *path, size_t size, char *err, size_t errlen);
/* Gives up f's lock on PATH.lock (the image stays in f); nothing when f holds none. */
void file_nvm_close(file_nvm_t *f);
/* file_nvm_check_path: something other than a regular file is at PATH. */
#define FILE_NVM_NOT_FILE (-1)
/* file_nvm_check_path: PATH is in use, or its directory is missing or not writable. */
#define FILE_NVM_UNUSABLE (-2)
/* Whether path can hold an image without opening it (a FIFO would block the open): 0 when it is
 * a regular file or nothing is there (a write creates it) in a writable directory, and no other
 * process holds it. Else FILE_NVM_NOT_FILE with "PATH: a FIFO, not a regular file" (a directory,
 * a character device ...) in err, or FILE_NVM_UNUSABLE with "PATH: the directory DIR does not
 * exist", "PATH: the directory DIR is not writable (REASON)", "PATH: PATH.lock is a symbolic
 * link (dfp-sim writes no file through a link)" (the same for PATH.tmp and PATH itself) or
 * "PATH: in use by another process (pid N, lock PATH.lock)". Checks without taking the lock:
 * file_nvm_open takes it. */
int file_nvm_check_path(const char *path, char *err, size_t errlen);
hal_nvm_t file_nvm_hal(file_nvm_t *f);
/* CRC-32 (IEEE 802.3, reflected, as zlib), exposed for tests that build images. */
uint32_t file_nvm_crc32(uint32_t crc, const uint8_t *p, size_t n);

#endif
