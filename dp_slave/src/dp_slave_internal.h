/* What the two halves of the slave share: the FDL station (fdl_station.c: baud, address filter,
 * function codes, FCB retry cache, reply encoding and timing) and the DP slave machine
 * (dp_slave.c: the service table applied, the DDLM services, watchdog). Not installed. */
#ifndef DP_SLAVE_INTERNAL_H
#define DP_SLAVE_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/dp_slave.h"
#include "dp_slave/fdl_frame.h"

void dp_slave_emit(dp_slave_t *s, dp_event_type_t type, hal_time_us_t t, uint32_t value,
                   uint8_t master);

/* DP slave machine: one request that passed the FDL station (addressed to this station, or a
 * broadcast SDN). sdn = sent without reply. Leaves the reply, if any, in s->tx. */
void dp_slave_request(dp_slave_t *s, const fdl_msg_t *m, bool sdn, hal_time_us_t t);

/* FDL station: the reply to send (s->tx, s->tx_len), built in s->tx_buf or framed where its DU
 * lies. */
void fdl_station_reply_sc(dp_slave_t *s);
/* Sends the reply built so far at once, before the service's remaining work; the SRD path then
 * caches it without sending it again. Only for a reply the remaining work cannot change. */
void fdl_station_send_now(dp_slave_t *s, hal_time_us_t request_end);
void fdl_station_reply_framed(dp_slave_t *s, const fdl_msg_t *m, uint8_t code, bool saps,
                              uint8_t *buf, size_t du_len, uint8_t du_sum);
void fdl_station_reply_plain(dp_slave_t *s, const fdl_msg_t *m, uint8_t code,
                             const uint8_t *data, size_t len);
void fdl_station_reply_sap(dp_slave_t *s, const fdl_msg_t *m, const uint8_t *data, size_t len);
void fdl_station_reply_rs(dp_slave_t *s, const fdl_msg_t *m);

/* True when a cached reply points into buf (one of the Data_Exchange buffers); with forget,
 * those cached replies are dropped. */
bool fdl_station_references(dp_slave_t *s, const uint8_t *buf, bool forget);
/* FDL station: a complete telegram is in s->rx. */
void fdl_station_frame(dp_slave_t *s);
/* The rate or min TSDR changed: recompute what the reply path needs of them. */
void fdl_station_timing_changed(dp_slave_t *s);
/* Whether the frame last handed to the transmitter (which it may still be sending) lies in the
 * reply buffer buf: one a new request has not yet proven finished. */
static inline bool fdl_station_sending_from(const dp_slave_t *s, const uint8_t *buf)
{
    return (uintptr_t)s->tx_last - (uintptr_t)buf < FDL_TX_HEADROOM;
}
/* After a reply: the FCB slot a new master would take over. */
void fdl_station_prepare(dp_slave_t *s);
/* After wd_on or wd_time_ms changed: the baud control time follows the watchdog. */
void fdl_station_watchdog_changed(dp_slave_t *s);
/* FDL station: baud search start and its timers; returns the merged next deadline. */
void fdl_station_start_baud(dp_slave_t *s, hal_time_us_t now);
hal_time_us_t fdl_station_poll(dp_slave_t *s, hal_time_us_t now);

#endif
