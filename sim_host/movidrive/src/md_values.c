/* The emulated MOVIDRIVE's parameter values in RAM: the generated table looked up by index,
 * range and enumeration checks, factory defaults. */
#include <string.h>

#include "md_internal.h"
#include "md_params.h"

int md_find_def(const movidrive_t *md, uint16_t index)
{
    size_t lo = 0;
    size_t hi = md->num_defs;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (md->defs[mid].index == index) {
            return (int)mid;
        }
        if (md->defs[mid].index < index) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return -1;
}

int32_t md_ram_value(const movidrive_t *md, uint16_t index)
{
    int k = md_find_def(md, index);
    return k < 0 ? 0 : md->ram[k];
}

void md_set_ram_value(movidrive_t *md, uint16_t index, int32_t value)
{
    int k = md_find_def(md, index);
    if (k >= 0) {
        md->ram[k] = value;
    }
}

bool md_value_in_range(const md_param_def_t *d, int32_t value)
{
    if (d->flags & MD_PF_UNSIGNED) {
        if ((d->flags & MD_PF_HAS_MIN) && (uint32_t)value < (uint32_t)d->min) {
            return false;
        }
        if ((d->flags & MD_PF_HAS_MAX) && (uint32_t)value > (uint32_t)d->max) {
            return false;
        }
    } else {
        if ((d->flags & MD_PF_HAS_MIN) && value < d->min) {
            return false;
        }
        if ((d->flags & MD_PF_HAS_MAX) && value > d->max) {
            return false;
        }
    }
    return d->enum_mask == 0u || (value >= 0 && value < 32 && (d->enum_mask >> value) & 1u);
}

void md_load_defaults(movidrive_t *md, bool keep_read_only)
{
    for (size_t k = 0; k < md->num_defs; k++) {
        if (keep_read_only && (md->defs[k].flags & MD_PF_READ_ONLY)) {
            continue;
        }
        md->ram[k] = md->defs[k].def;
        md->ee[k] = md->defs[k].def;
    }
    memset(md->ipos, 0, sizeof md->ipos);
    memset(md->ee_ipos, 0, sizeof md->ee_ipos);
}

const md_param_def_t *movidrive_param_def(const movidrive_t *md, uint16_t index)
{
    if (md_is_ipos(index)) {
        return &md_ipos_def;
    }
    int k = md_find_def(md, index);
    return k < 0 ? NULL : &md->defs[k];
}
