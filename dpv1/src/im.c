#include "dpv1/im.h"

#include <string.h>

#include "dpv1/dpv1_wire.h"
#include "hal/hal_byte_order.h"

static void put_text(uint8_t *p, const char *s, size_t width)
{
    size_t n = 0;
    while (n < width && s[n] != '\0') {
        p[n] = (uint8_t)s[n];
        n++;
    }
    memset(&p[n], ' ', width - n);
}

void im_build_record0(const im_identity_t *id, uint8_t out[IM_RECORD_LEN])
{
    memset(out, 0, IM_RECORD_LEN); /* the manufacturer header: unused */
    size_t n = IM0_HEADER_LEN;
    hal_put_be16(&out[n], id->manufacturer_id);
    n += 2u;
    put_text(&out[n], id->order_id, IM0_ORDER_ID_LEN);
    n += IM0_ORDER_ID_LEN;
    put_text(&out[n], id->serial, IM0_SERIAL_LEN);
    n += IM0_SERIAL_LEN;
    hal_put_be16(&out[n], id->hardware_revision);
    n += 2u;
    memcpy(&out[n], id->software_revision, IM0_SOFTWARE_REVISION_LEN);
    n += IM0_SOFTWARE_REVISION_LEN;
    hal_put_be16(&out[n], id->revision_counter);
    n += 2u;
    hal_put_be16(&out[n], id->profile_id);
    n += 2u;
    hal_put_be16(&out[n], id->profile_specific_type);
    n += 2u;
    out[n++] = IM0_VERSION_MAJOR;
    out[n++] = IM0_VERSION_MINOR;
    hal_put_be16(&out[n], IM0_SUPPORTED_IM1_TO_IM4);
}

void im_init(im_t *im, const im_identity_t *id, hal_nvm_t nvm, size_t nvm_offset)
{
    memset(im, 0, sizeof *im);
    im->id = *id;
    im->nvm = nvm;
    im->nvm_offset = nvm_offset;
    if (nvm.ops == NULL) {
        return;
    }
    uint8_t magic[4];
    if (nvm.ops->read(nvm.ctx, nvm_offset, magic, sizeof magic) == 0 &&
        ((uint32_t)magic[0] << 24 | (uint32_t)magic[1] << 16 | (uint32_t)magic[2] << 8 |
         magic[3]) == IM_NVM_MAGIC &&
        nvm.ops->read(nvm.ctx, nvm_offset + 4u, im_record_at(im, 0), sizeof im->image - 4u) == 0) {
        im->nvm_ok = true;
        return;
    }
    memset(im_record_at(im, 0), 0, sizeof im->image - 4u);
}

static int store(im_t *im)
{
    if (im->nvm.ops == NULL) {
        return 0; /* no storage on this card: kept until power-off */
    }
    hal_put_be32(im->image, IM_NVM_MAGIC);
    /* One write of the whole image: the backend keeps it all-old or all-new. */
    return im->nvm.ops->write(im->nvm.ctx, im->nvm_offset, im->image, sizeof im->image);
}

uint8_t im_write(im_t *im, const uint8_t *data, size_t len, uint16_t *selected)
{
    if (len < IM_CALL_HEADER_LEN || data[0] != IM_FN_CALL || data[1] != 0u) {
        return DPV1_ERR_INVALID_RANGE;
    }
    uint16_t fi = (uint16_t)((data[2] << 8) | data[3]);
    if (fi < IM_INDEX_0 || fi > IM_INDEX_LAST) {
        return DPV1_ERR_INVALID_INDEX;
    }
    if (len == IM_CALL_HEADER_LEN) {
        *selected = fi; /* selects the record the next Read returns */
        return 0;
    }
    if (len != IM_CALL_HEADER_LEN + IM_RECORD_LEN) {
        return DPV1_ERR_WRITE_LENGTH;
    }
    if (fi == IM_INDEX_0) {
        return DPV1_ERR_ACCESS_DENIED;
    }
    uint8_t *rec = im_record_at(im, fi - IM_INDEX_0 - 1u);
    uint8_t old[IM_RECORD_LEN];
    memcpy(old, rec, sizeof old);
    memcpy(rec, &data[IM_CALL_HEADER_LEN], IM_RECORD_LEN);
    if (store(im) != 0) {
        memcpy(rec, old, sizeof old);
        return DPV1_ERR_WRITE_ERROR;
    }
    *selected = fi;
    return 0;
}

uint8_t im_read(const im_t *im, uint16_t selected, uint8_t *out, size_t max, size_t *len)
{
    if (max < IM_CALL_HEADER_LEN + IM_RECORD_LEN) {
        return DPV1_ERR_INVALID_RANGE;
    }
    out[0] = IM_FN_CALL;
    out[1] = 0;
    if (selected < IM_INDEX_0 || selected > IM_INDEX_LAST) {
        selected = IM_INDEX_0;
    }
    out[2] = (uint8_t)(selected >> 8);
    out[3] = (uint8_t)selected;
    if (selected == IM_INDEX_0) {
        im_build_record0(&im->id, &out[IM_CALL_HEADER_LEN]);
    } else {
        memcpy(&out[IM_CALL_HEADER_LEN], &im->image[4u + (selected - IM_INDEX_0 - 1u) * IM_RECORD_LEN], IM_RECORD_LEN);
    }
    *len = IM_CALL_HEADER_LEN + IM_RECORD_LEN;
    return 0;
}
