/* Identification & Maintenance through the DP-V1 call service on index 255 (protocol.md §A7,
 * docs/dpv1.md). I&M0 comes from the card's identity; I&M1..I&M4 are written by the master and
 * kept in the card's non-volatile storage. */
#ifndef DPV1_IM_H
#define DPV1_IM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_nvm.h"

#include "dpv1/dpv1_wire.h"

#define IM_WRITABLE 4u
#define IM_NVM_MAGIC 0x494D3031u /* "IM01" */
#define IM_NVM_SIZE (4u + IM_WRITABLE * IM_RECORD_LEN)

typedef struct im_identity {
    uint16_t manufacturer_id;  /* 0x010A = SEW-EURODRIVE */
    char order_id[IM0_ORDER_ID_LEN + 1u]; /* blank-padded in the record */
    char serial[IM0_SERIAL_LEN + 1u];
    uint16_t hardware_revision;
    uint8_t software_revision[IM0_SOFTWARE_REVISION_LEN]; /* 'V', major, minor, bugfix */
    uint16_t revision_counter;
    uint16_t profile_id;
    uint16_t profile_specific_type;
} im_identity_t;

typedef struct im {
    im_identity_t id;
    hal_nvm_t nvm;
    size_t nvm_offset;
    /* As stored: the magic, then I&M1..4 (im_record_at()); written as it is, with no staging copy
     * on the stack. */
    uint8_t image[IM_NVM_SIZE];
    bool nvm_ok;
} im_t;

/* Record I&M1+i (i = 0..3). */
static inline uint8_t *im_record_at(im_t *im, unsigned i)
{
    return &im->image[4u + i * IM_RECORD_LEN];
}

/* Loads I&M1..4 from nvm (blank records if there is none or it is not ours). */
void im_init(im_t *im, const im_identity_t *id, hal_nvm_t nvm, size_t nvm_offset);
/* Write.req on index 255: 0 or a DP-V1 Error_Code_1 (B0 unknown FI_Index, B1 length, B6 I&M0
 * is read-only, B7 call header, A1 storage failed). *selected is the connection's choice of the
 * record its next Read returns: each master has its own, so two cannot mix up their calls. */
uint8_t im_write(im_t *im, const uint8_t *data, size_t len, uint16_t *selected);
/* Read.req on index 255: call header + the selected record. 0 or an Error_Code_1. */
uint8_t im_read(const im_t *im, uint16_t selected, uint8_t *out, size_t max, size_t *len);
void im_build_record0(const im_identity_t *id, uint8_t out[IM_RECORD_LEN]);

#endif
