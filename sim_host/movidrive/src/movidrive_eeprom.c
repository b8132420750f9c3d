/* The emulated MOVIDRIVE's EEPROM image in a hal_nvm: layout (movidrive.h, README.md
 * "EEPROM"), saving one record or the whole image, loading with every check a damaged or
 * foreign image needs. Crash safety comes from the NVM: each write here is one hal_nvm write,
 * atomic by the HAL contract. */
#include <stdio.h>

#include "hal/hal_byte_order.h"
#include "movidrive_internal.h"
#include "movidrive_params.h"

#define EE_IPOS_BYTES 4u
/* Largest image: header + every parameter + the IPOS variables. */
#define EE_MAX_IMAGE                                                                               \
    (MOVIDRIVE_EE_HEADER + MOVIDRIVE_MAX_PARAMS * MOVIDRIVE_EE_RECORD +                            \
     MOVIDRIVE_IPOS_VARS * EE_IPOS_BYTES)

static bool is_non_volatile(const movidrive_param_def_t *d)
{
    return (d->flags & MOVIDRIVE_PF_NON_VOLATILE) != 0u;
}

/* Records the current table puts in the image. */
static uint32_t ee_records(const movidrive_t *md)
{
    uint32_t n = 0;
    for (size_t k = 0; k < md->num_defs; k++) {
        n += is_non_volatile(&md->defs[k]) ? 1u : 0u;
    }
    return n;
}

size_t movidrive_eeprom_size(void)
{
    size_t n = 0;
    for (size_t k = 0; k < movidrive_params_count; k++) {
        n += is_non_volatile(&movidrive_params[k]) ? 1u : 0u;
    }
    return MOVIDRIVE_EE_HEADER + n * MOVIDRIVE_EE_RECORD +
           (size_t)MOVIDRIVE_IPOS_VARS * EE_IPOS_BYTES;
}

static int ee_write(movidrive_t *md, size_t offset, const uint8_t *data, size_t len)
{
    md->eeprom_writes++;
    return md->cfg.eeprom.ops->write(md->cfg.eeprom.ctx, offset, data, len);
}

/* Writes the records of defs[first..last] that are N parameters to out; returns the bytes. */
static size_t put_records(const movidrive_t *md, size_t first, size_t last, uint8_t *out)
{
    size_t n = 0;
    for (size_t k = first; k <= last; k++) {
        if (is_non_volatile(&md->defs[k])) {
            hal_put_be16(out + n, md->defs[k].index);
            hal_put_be32(out + n + 2, (uint32_t)md->ee[k]);
            n += MOVIDRIVE_EE_RECORD;
        }
    }
    return n;
}

int movidrive_ee_save_all(movidrive_t *md)
{
    if (!md->ee_usable) {
        return 0;
    }
    uint8_t img[EE_MAX_IMAGE];
    hal_put_be32(img, MOVIDRIVE_EE_MAGIC);
    hal_put_be16(img + 4, MOVIDRIVE_EE_VERSION);
    hal_put_be16(img + 6, (uint16_t)ee_records(md));
    hal_put_be16(img + 8, MOVIDRIVE_IPOS_VARS);
    hal_put_be16(img + 10, 0);
    size_t len = MOVIDRIVE_EE_HEADER;
    if (md->num_defs > 0) {
        len += put_records(md, 0, md->num_defs - 1u, img + len);
    }
    for (size_t i = 0; i < MOVIDRIVE_IPOS_VARS; i++) {
        hal_put_be32(img + len, (uint32_t)md->ee_ipos[i]);
        len += EE_IPOS_BYTES;
    }
    if (ee_write(md, 0, img, len) != 0) {
        return -1;
    }
    md->ee_layout_ok = true;
    return 0;
}

int movidrive_ee_save_params(movidrive_t *md, size_t first, size_t last)
{
    if (!md->ee_usable) {
        return 0;
    }
    if (!md->ee_layout_ok) {
        return movidrive_ee_save_all(md);
    }
    size_t slot = 0;
    for (size_t k = 0; k < first; k++) {
        slot += is_non_volatile(&md->defs[k]) ? 1u : 0u;
    }
    uint8_t buf[MOVIDRIVE_MAX_PARAMS * MOVIDRIVE_EE_RECORD];
    size_t n = put_records(md, first, last, buf);
    if (n == 0) {
        return 0;
    }
    return ee_write(md, MOVIDRIVE_EE_HEADER + slot * MOVIDRIVE_EE_RECORD, buf, n);
}

int movidrive_ee_save_ipos(movidrive_t *md, size_t i)
{
    if (!md->ee_usable) {
        return 0;
    }
    if (!md->ee_layout_ok) {
        return movidrive_ee_save_all(md);
    }
    uint8_t buf[EE_IPOS_BYTES];
    hal_put_be32(buf, (uint32_t)md->ee_ipos[i]);
    return ee_write(md,
                    MOVIDRIVE_EE_HEADER + ee_records(md) * MOVIDRIVE_EE_RECORD + i * EE_IPOS_BYTES,
                    buf, EE_IPOS_BYTES);
}

static bool all_bytes(const uint8_t *p, size_t n, uint8_t v)
{
    for (size_t i = 0; i < n; i++) {
        if (p[i] != v) {
            return false;
        }
    }
    return true;
}

/* Outcome of the header checks. */
typedef enum { EE_HEADER_BAD = -1, EE_HEADER_OK = 0, EE_HEADER_BLANK = 1 } ee_header_t;

/* The 12-byte header against an NVM of `have` bytes; on OK, *len = the image's bytes and
 * *nrec = its records. */
static ee_header_t ee_check_header(const uint8_t *img, size_t have, size_t *len, unsigned *nrec,
                                   char *err, size_t errlen)
{
    if (all_bytes(img, MOVIDRIVE_EE_HEADER, 0xFFu) || all_bytes(img, MOVIDRIVE_EE_HEADER, 0x00u)) {
        return EE_HEADER_BLANK; /* first start */
    }
    uint32_t magic = hal_get_be32(img);
    if (magic != MOVIDRIVE_EE_MAGIC) {
        (void)snprintf(err, errlen,
                       "EEPROM holds no MOVIDRIVE image (magic 0x%08X, expected 0x%08X): factory "
                       "defaults used",
                       (unsigned)magic, (unsigned)MOVIDRIVE_EE_MAGIC);
        return EE_HEADER_BAD;
    }
    unsigned version = hal_get_be16(img + 4);
    unsigned records = hal_get_be16(img + 6);
    unsigned nipos = hal_get_be16(img + 8);
    if (version != MOVIDRIVE_EE_VERSION) {
        (void)snprintf(err, errlen,
                       "EEPROM image version %u not supported (%u): factory defaults used",
                       version, (unsigned)MOVIDRIVE_EE_VERSION);
        return EE_HEADER_BAD;
    }
    size_t bytes =
        MOVIDRIVE_EE_HEADER + (size_t)records * MOVIDRIVE_EE_RECORD + (size_t)nipos * EE_IPOS_BYTES;
    if (nipos != MOVIDRIVE_IPOS_VARS || records > MOVIDRIVE_MAX_PARAMS || bytes > have) {
        (void)snprintf(err, errlen,
                       "EEPROM image header inconsistent (%u records, %u IPOS variables): "
                       "factory defaults used",
                       records, nipos);
        return EE_HEADER_BAD;
    }
    *len = bytes;
    *nrec = records;
    return EE_HEADER_OK;
}

/* Takes the records into ram[]/ee[], matched by index, and the IPOS variables after them.
 * Returns the number of values out of range (left at their defaults); sets ee_layout_ok when
 * the records are exactly this table's N parameters in order. */
static unsigned ee_take_records(movidrive_t *md, const uint8_t *img, unsigned nrec)
{
    bool layout = nrec == ee_records(md);
    unsigned bad = 0;
    size_t slot_k = 0;
    const uint8_t *p = img + MOVIDRIVE_EE_HEADER;
    for (unsigned r = 0; r < nrec; r++, p += MOVIDRIVE_EE_RECORD) {
        uint16_t index = hal_get_be16(p);
        int32_t v = (int32_t)hal_get_be32(p + 2);
        while (slot_k < md->num_defs && !is_non_volatile(&md->defs[slot_k])) {
            slot_k++;
        }
        if (slot_k >= md->num_defs || md->defs[slot_k].index != index) {
            layout = false;
        }
        slot_k++;
        int k = movidrive_find_def(md, index);
        if (k < 0 || !is_non_volatile(&md->defs[k])) {
            continue; /* a parameter this table no longer has: dropped at the next save */
        }
        if (!movidrive_value_in_range(&md->defs[k], v)) {
            bad++;
            continue;
        }
        md->ram[k] = v;
        md->ee[k] = v;
    }
    for (size_t i = 0; i < MOVIDRIVE_IPOS_VARS; i++, p += EE_IPOS_BYTES) {
        md->ipos[i] = md->ee_ipos[i] = (int32_t)hal_get_be32(p);
    }
    md->ee_layout_ok = layout;
    return bad;
}

int movidrive_ee_load(movidrive_t *md, char *err, size_t errlen)
{
    const hal_nvm_t *nvm = &md->cfg.eeprom;
    if (nvm->ops == NULL) {
        return 0;
    }
    size_t need = movidrive_eeprom_size();
    size_t have = nvm->ops->size(nvm->ctx);
    if (have < need) {
        (void)snprintf(err, errlen,
                       "EEPROM too small (%zu bytes, the image needs %zu): not stored", have,
                       need);
        return -1;
    }
    md->ee_usable = true;
    uint8_t img[EE_MAX_IMAGE];
    if (nvm->ops->read(nvm->ctx, 0, img, MOVIDRIVE_EE_HEADER) != 0) {
        (void)snprintf(err, errlen,
                       "EEPROM unreadable (corrupt or damaged image): factory defaults used");
        return -1;
    }
    size_t len = 0;
    unsigned nrec = 0;
    ee_header_t header = ee_check_header(img, have, &len, &nrec, err, errlen);
    if (header != EE_HEADER_OK) {
        return header == EE_HEADER_BLANK ? 0 : -1;
    }
    if (nvm->ops->read(nvm->ctx, 0, img, len) != 0) {
        (void)snprintf(err, errlen, "EEPROM unreadable: factory defaults used");
        return -1;
    }
    unsigned bad = ee_take_records(md, img, nrec);
    if (bad != 0) {
        (void)snprintf(err, errlen, "EEPROM: %u stored values out of range, defaults used for them",
                       bad);
        return -1;
    }
    return 0;
}
