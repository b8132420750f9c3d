#include "dp_master/param_channel.h"

#include <stdio.h>
#include <string.h>

void dp_master_param_sync(dp_master_param_t *p, const uint8_t in[ML_TELEGRAM_LEN])
{
    p->handshake = (uint8_t)(in[ML_OFF_MANAGEMENT] & ML_MGMT_HANDSHAKE);
    p->busy = false;
}

void dp_master_param_start(dp_master_param_t *p, uint8_t service, uint16_t index, uint32_t value,
                     uint8_t out[ML_TELEGRAM_LEN])
{
    p->handshake = (uint8_t)(p->handshake ^ ML_MGMT_HANDSHAKE);
    p->req[ML_OFF_MANAGEMENT] =
        (uint8_t)(p->handshake | ML_MGMT_LENGTH_4 | (service & ML_MGMT_SERVICE_MASK));
    p->req[ML_OFF_RESERVED] = 0;
    p->req[ML_OFF_INDEX_HIGH] = (uint8_t)(index >> 8);
    p->req[ML_OFF_INDEX_LOW] = (uint8_t)index;
    ml_put_data(p->req, value);
    p->busy = true;
    memcpy(out, p->req, ML_TELEGRAM_LEN);
}

bool dp_master_param_done(dp_master_param_t *p, const uint8_t in[ML_TELEGRAM_LEN])
{
    if (!p->busy || (in[ML_OFF_MANAGEMENT] & ML_MGMT_HANDSHAKE) != p->handshake ||
        ml_index(in) != ml_index(p->req)) {
        return false;
    }
    p->busy = false;
    return true;
}

const char *ml_service_name(uint8_t service)
{
    static const char *const names[] = {"no service", "read", "write", "write volatile",
                                        "read minimum", "read maximum", "read default",
                                        "read scale", "read attribute"};
    return service <= ML_SVC_LAST ? names[service] : "reserved service";
}

static const char *other_text(uint8_t add)
{
    switch (add) {
    case 0x10: return "illegal parameter index";
    case 0x11: return "function/parameter not implemented";
    case 0x12: return "read access only";
    case 0x13: return "parameter lock active";
    case 0x14: return "factory setting active";
    case 0x15: return "value too high";
    case 0x16: return "value too low";
    case 0x17: return "required option card missing";
    case 0x18: return "error in system software";
    case 0x19: return "access only via RS-485 process interface X13";
    case 0x1A: return "access only via RS-485 diagnostic interface";
    case 0x1B: return "parameter is access-protected";
    case 0x1C: return "controller inhibit required";
    case 0x1D: return "value not permitted";
    case 0x1E: return "factory setting was activated";
    case 0x1F: return "parameter not saved in EEPROM";
    case 0x20: return "cannot be changed with output stage enabled";
    case 0x23: return "only while the IPOS program is stopped";
    case 0x24: return "only with auto-setup off";
    default: return "unknown additional code";
    }
}

size_t ml_error_text(const uint8_t rsp[ML_TELEGRAM_LEN], char *out, size_t max)
{
    uint8_t cls = rsp[4];
    uint8_t code = rsp[5];
    uint16_t add = (uint16_t)((rsp[6] << 8) | rsp[7]);
    int n;
    if (cls == ML_CLASS_OTHER) {
        n = snprintf(out, max, "class 8, additional code 0x%02X: %s", add & 0xFFu,
                     other_text((uint8_t)add));
    } else if (cls == ML_CLASS_SERVICE && code == ML_CODE_ILLEGAL_PARAMETER) {
        n = snprintf(out, max, "class 5 code 5: wrong coding of the management or reserved octet");
    } else if (cls == ML_CLASS_ACCESS && code == ML_CODE_TYPE_CONFLICT) {
        n = snprintf(out, max, "class 6 code 8: data length other than 4 octets");
    } else if (cls == ML_CLASS_ACCESS && code == ML_CODE_HARDWARE_FAULT) {
        n = snprintf(out, max, "class 6 code 2: card <-> inverter communication fault");
    } else {
        n = snprintf(out, max, "class %u code %u additional 0x%04X", cls, code, add);
    }
    return n < 0 ? 0u : (size_t)n;
}
