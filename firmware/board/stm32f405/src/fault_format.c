/* Text form of the fault record, and its life after a start took it; separate from the
 * handlers and main so host tests can check them. */
#include "board/board.h"

static unsigned put_str(char *out, unsigned pos, unsigned max, const char *s)
{
    while (*s != '\0' && pos + 1u < max) {
        out[pos++] = *s++;
    }
    return pos;
}

static unsigned put_hex(char *out, unsigned pos, unsigned max, uint32_t v)
{
    static const char digits[] = "0123456789abcdef";
    pos = put_str(out, pos, max, "0x");
    for (int sh = 28; sh >= 0; sh -= 4) {
        if (pos + 1u < max) {
            out[pos++] = digits[(v >> sh) & 0xFu];
        }
    }
    return pos;
}

static const char *exception_name(uint32_t n)
{
    switch (n) {
    case 2: return "NMI";
    case 3: return "HardFault";
    case 4: return "MemManage";
    case 5: return "BusFault";
    case 6: return "UsageFault";
    default: return n >= 16u ? "unexpected IRQ" : "exception";
    }
}

unsigned board_fault_format(const board_fault_record_t *r, char *out, unsigned max)
{
    if (max == 0u) {
        return 0;
    }
    unsigned p = 0;
    if (r->magic != BOARD_FAULT_MAGIC) {
        p = put_str(out, p, max, "fault: none");
        out[p] = '\0';
        return p;
    }
    p = put_str(out, p, max, "fault: ");
    p = put_str(out, p, max, exception_name(r->exception));
    const struct {
        const char *name;
        uint32_t v;
    } f[] = {
        {" exc=", r->exception}, {" pc=", r->pc},       {" lr=", r->lr},     {" sp=", r->sp},
        {" xpsr=", r->xpsr},     {" cfsr=", r->cfsr},   {" hfsr=", r->hfsr}, {" mmfar=", r->mmfar},
        {" bfar=", r->bfar},     {" r0=", r->r0},       {" r1=", r->r1},     {" r2=", r->r2},
        {" r3=", r->r3},         {" r12=", r->r12},     {" count=", r->count},
    };
    for (unsigned i = 0; i < sizeof f / sizeof f[0]; i++) {
        p = put_str(out, p, max, f[i].name);
        p = put_hex(out, p, max, f[i].v);
    }
    out[p] = '\0';
    return p;
}

void board_fault_mark_shown(board_fault_record_t *r)
{
    if (r->magic == BOARD_FAULT_MAGIC) {
        r->magic = BOARD_FAULT_SHOWN; /* the fault handler starts the count afresh from it */
    }
}
