/* The emulated MOVIDRIVE's parameter values in RAM: the generated table looked up by index,
 * range and enumeration checks, factory defaults. */
#include <string.h>

#include "movidrive_internal.h"
#include "movidrive_params.h"

void movidrive_build_slots(movidrive_t *md)
{
    md->slot_defs = NULL; /* until the table is complete: the binary search */
    size_t n = md->num_defs;
    if (n == 0u || n > MOVIDRIVE_MAX_PARAMS) {
        return;
    }
    md->slot_base = md->defs[0].index;
    memset(md->slot, 0xFF, sizeof md->slot); /* every slot -1 */
    for (size_t k = 0; k < n; k++) {
        unsigned off = (unsigned)md->defs[k].index - md->slot_base;
        if (off >= MOVIDRIVE_SLOT_SPAN) {
            return; /* wider than the table (or not sorted) */
        }
        md->slot[off] = (int16_t)k;
    }
    md->slot_defs = md->defs;
    md->slot_num = n;
}

int movidrive_find_def_search(const movidrive_t *md, uint16_t index)
{
    /* A binary search without a branch on the comparison, which the CPU cannot predict, ending
     * on the last entry at or below index. */
    size_t n = md->num_defs;
    if (n == 0u) {
        return -1;
    }
    const movidrive_param_def_t *base = md->defs;
    while (n > 1u) {
        size_t half = n / 2u;
        base = base[half].index <= index ? base + half : base;
        n -= half;
    }
    return base->index == index ? (int)(base - md->defs) : -1;
}

void movidrive_set_ram_value(movidrive_t *md, uint16_t index, int32_t value)
{
    int k = movidrive_find_def(md, index);
    if (k >= 0) {
        md->ram[k] = value;
    }
}

bool movidrive_value_in_range(const movidrive_param_def_t *d, int32_t value)
{
    if (d->flags & MOVIDRIVE_PF_UNSIGNED) {
        if ((d->flags & MOVIDRIVE_PF_HAS_MIN) && (uint32_t)value < (uint32_t)d->min) {
            return false;
        }
        if ((d->flags & MOVIDRIVE_PF_HAS_MAX) && (uint32_t)value > (uint32_t)d->max) {
            return false;
        }
    } else {
        if ((d->flags & MOVIDRIVE_PF_HAS_MIN) && value < d->min) {
            return false;
        }
        if ((d->flags & MOVIDRIVE_PF_HAS_MAX) && value > d->max) {
            return false;
        }
    }
    return d->enum_mask == 0u || (value >= 0 && value < 32 && (d->enum_mask >> value) & 1u);
}

void movidrive_load_defaults(movidrive_t *md, bool keep_read_only)
{
    for (size_t k = 0; k < md->num_defs; k++) {
        if (keep_read_only && (md->defs[k].flags & MOVIDRIVE_PF_READ_ONLY)) {
            continue;
        }
        md->ram[k] = md->defs[k].def;
        md->ee[k] = md->defs[k].def;
    }
    memset(md->ipos, 0, sizeof md->ipos);
    memset(md->ee_ipos, 0, sizeof md->ee_ipos);
}

const movidrive_param_def_t *movidrive_param_def(const movidrive_t *md, uint16_t index)
{
    if (movidrive_is_ipos(index)) {
        return &movidrive_ipos_def;
    }
    int k = movidrive_find_def(md, index);
    return k < 0 ? NULL : &md->defs[k];
}
