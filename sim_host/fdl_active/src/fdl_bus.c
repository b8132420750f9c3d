/* Bus parameters: the DP profile's values per rate, the USB profile, the rules between them. */
#include <stdio.h>

#include "dp_slave/fdl_wire.h"
#include "fdl_active/fdl_active.h"

typedef struct profile_row {
    uint32_t baud;
    uint16_t tsl;
    uint16_t max_tsdr;
    uint8_t tset;
    uint8_t tqui;
    uint8_t retry;
} profile_row_t;

/* The values PLC configuration tools propose for the DP profile (IEC 61784-1 CP 3/1 bus
 * parameter sets; the same numbers appear in every DP master's GSD defaults). */
static const profile_row_t dp_rows[] = {
    {9600u, 100u, 60u, 1u, 0u, 1u},       {19200u, 100u, 60u, 1u, 0u, 1u},
    {45450u, 640u, 400u, 95u, 0u, 1u},    {93750u, 100u, 60u, 1u, 0u, 1u},
    {187500u, 100u, 60u, 1u, 0u, 1u},     {500000u, 200u, 100u, 1u, 0u, 1u},
    {1500000u, 300u, 150u, 1u, 0u, 1u},   {3000000u, 400u, 250u, 4u, 3u, 2u},
    {6000000u, 600u, 450u, 8u, 6u, 3u},   {12000000u, 1000u, 800u, 16u, 9u, 4u},
};

/* A USB adapter hands characters over in batches of a millisecond or more, a PTY in whatever the
 * scheduler allows: the slot time must cover that, not the line. Every silent address of a GAP
 * sweep then costs that slot time, so the profile keeps the GAP to the addresses a bench uses
 * (HSA 31) and sweeps it rarely (G 100): a lone master spends about a fifth of its visits on
 * it instead of nearly all. */
#define USB_TSL_MS 100u
#define USB_MAX_TSDR_MS 10u
#define USB_TTR_MS 2000u
#define USB_HSA 31u
#define USB_GAP_FACTOR 100u
#define DP_TTR_BITS 30000u

static uint32_t ms_bits(uint32_t baud, uint32_t ms)
{
    return (uint32_t)((uint64_t)baud * ms / 1000u);
}

void fdl_bus_params_default(fdl_bus_params_t *p, uint32_t baud, fdl_bus_profile_t profile)
{
    const profile_row_t *row = &dp_rows[1];
    for (size_t i = 0; i < sizeof dp_rows / sizeof dp_rows[0]; i++) {
        if (dp_rows[i].baud == baud) {
            row = &dp_rows[i];
        }
    }
    *p = (fdl_bus_params_t){.baud = baud, .tsl_bits = row->tsl,
                            .min_tsdr_bits = FDL_MIN_TSDR_DEFAULT_BITS,
                            .max_tsdr_bits = row->max_tsdr, .tset_bits = row->tset,
                            .tqui_bits = row->tqui, .ttr_bits = DP_TTR_BITS, .gap_factor = 10u,
                            .hsa = FDL_ACTIVE_HSA_MAX, .max_retry = row->retry};
    if (profile == FDL_BUS_PROFILE_USB) {
        p->tsl_bits = ms_bits(baud, USB_TSL_MS);
        p->max_tsdr_bits = ms_bits(baud, USB_MAX_TSDR_MS);
        p->ttr_bits = ms_bits(baud, USB_TTR_MS);
        p->hsa = USB_HSA;
        p->gap_factor = USB_GAP_FACTOR;
    }
}

uint32_t fdl_bus_tid1_bits(const fdl_bus_params_t *p)
{
    uint32_t a = FDL_TSYN_BITS + p->tset_bits + p->tqui_bits;
    uint32_t b = 35u + 2u * p->tset_bits + p->tqui_bits;
    uint32_t t = a > b ? a : b;
    return t > p->min_tsdr_bits ? t : p->min_tsdr_bits;
}

uint32_t fdl_bus_tid2_bits(const fdl_bus_params_t *p)
{
    uint32_t a = FDL_TSYN_BITS + p->tset_bits + p->tqui_bits;
    return a > p->max_tsdr_bits ? a : p->max_tsdr_bits;
}

uint32_t fdl_bus_tto_bits(const fdl_bus_params_t *p, uint8_t ts)
{
    uint64_t t = (6u + 2u * (uint64_t)ts) * p->tsl_bits;
    return t > UINT32_MAX ? UINT32_MAX : (uint32_t)t;
}

uint32_t fdl_bus_us(const fdl_bus_params_t *p, uint32_t bits)
{
    return hal_uart_bits_us(p->baud, bits);
}

/* Station timers are 32-bit microseconds compared by difference: no interval may reach 2^31. */
#define TIME_LIMIT_S 2147u

static uint64_t bits_s(const fdl_bus_params_t *p, uint64_t bits)
{
    return p->baud == 0u ? 0u : bits / p->baud;
}

bool fdl_bus_params_check(const fdl_bus_params_t *p, char *why, size_t n)
{
    const char *rule = NULL;
    if (p->baud == 0u) {
        rule = "the rate must not be 0";
    } else if (p->min_tsdr_bits < FDL_MIN_TSDR_DEFAULT_BITS) {
        rule = "min TSDR must be at least 11 bit times";
    } else if (p->min_tsdr_bits > p->max_tsdr_bits) {
        rule = "min TSDR must not exceed max TSDR";
    } else if (p->tsl_bits <= p->max_tsdr_bits + 2u * p->tset_bits + p->tqui_bits + 11u) {
        rule = "TSL must exceed max TSDR + 2 TSET + TQUI + 11 (the reply's first character)";
    } else if (p->tsl_bits > 16777215u) {
        rule = "TSL must not exceed 16777215 bit times";
    } else if (p->ttr_bits < 256u) {
        rule = "TTR must be at least 256 bit times";
    } else if (p->gap_factor == 0u || p->gap_factor > 100u) {
        rule = "G (the GAP update factor) must be 1..100";
    } else if (p->hsa > FDL_ACTIVE_HSA_MAX) {
        rule = "HSA must be 0..126";
    } else if (p->max_retry > 7u) {
        rule = "the retry limit must be 0..7";
    } else if (bits_s(p, fdl_bus_tto_bits(p, FDL_ACTIVE_HSA_MAX)) >= TIME_LIMIT_S ||
               bits_s(p, p->ttr_bits) >= TIME_LIMIT_S) {
        rule = "TSL x 258 (the lost-token time-out of address 126) and TTR must each stay "
               "below 2147 s at this rate";
    }
    if (rule != NULL && why != NULL && n > 0u) {
        (void)snprintf(why, n, "%s", rule);
    }
    return rule == NULL;
}

bool fdl_bus_address_ok(const fdl_bus_params_t *p, uint8_t ts, char *why, size_t n)
{
    if (ts <= p->hsa) {
        return true;
    }
    if (why != NULL && n > 0u) {
        (void)snprintf(why, n, "address %u is above HSA %u: no master's GAP maintenance asks it, "
                       "so it could join no ring", ts, p->hsa);
    }
    return false;
}
