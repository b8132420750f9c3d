/* Helpers shared by the emulated-MOVIDRIVE tests: build a request, run one service. */
#ifndef TESTS_MOVIDRIVE_TEST_UTIL_H
#define TESTS_MOVIDRIVE_TEST_UTIL_H

#include <stdint.h>
#include <string.h>

#include "hal/hal_byte_order.h"
#include "movidrive/movidrive.h"

static inline void movidrive_req(uint8_t t[ML_TELEGRAM_LEN], uint8_t mgmt, uint16_t index,
                                 uint32_t data)
{
    memset(t, 0, ML_TELEGRAM_LEN);
    t[0] = mgmt;
    hal_put_be16(t + 2, index);
    ml_put_data(t, data);
}

/* One service; returns the response in rsp. */
static inline void movidrive_svc(movidrive_t *md, uint8_t mgmt, uint16_t index, uint32_t data,
                          uint8_t rsp[ML_TELEGRAM_LEN])
{
    uint8_t req[ML_TELEGRAM_LEN];
    movidrive_req(req, mgmt, index, data);
    movidrive_param(md, req, rsp);
}

/* Read: the value, or 0xDEADBEEF if the read failed. */
static inline uint32_t movidrive_read(movidrive_t *md, uint16_t index)
{
    uint8_t rsp[ML_TELEGRAM_LEN];
    movidrive_svc(md, 0x01, index, 0, rsp);
    return (rsp[0] & ML_MGMT_ERROR) ? 0xDEADBEEFu : ml_data(rsp);
}

/* Write (0x32) or write volatile (0x33): 0 or the class 8 additional code (0x100 + class for
 * other classes). */
static inline unsigned movidrive_write(movidrive_t *md, uint16_t index, uint32_t value,
                                       int non_volatile)
{
    uint8_t rsp[ML_TELEGRAM_LEN];
    movidrive_svc(md, non_volatile ? 0x32 : 0x33, index, value, rsp);
    if (!(rsp[0] & ML_MGMT_ERROR)) {
        return 0;
    }
    return rsp[4] == ML_CLASS_OTHER ? rsp[7] : 0x100u + rsp[4];
}

static inline void movidrive_po3(movidrive_t *md, uint16_t po1, uint16_t po2, uint16_t po3)
{
    const uint16_t po[3] = {po1, po2, po3};
    movidrive_process_outputs(md, po, 3);
}

static inline uint16_t movidrive_pi(const movidrive_t *md, uint8_t i)
{
    uint16_t pi[ML_MAX_PD];
    movidrive_process_inputs(md, pi, ML_MAX_PD);
    return pi[i];
}

#endif
