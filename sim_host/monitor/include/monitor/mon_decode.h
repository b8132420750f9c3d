/* What a monitored DP slave's octets mean, for the reports and the views: its Slave_Diag DU as
 * one line (the standard octets by their IEC 61158-6-3 names, then the extended diagnosis
 * blocks), and for a DFP21B (ident 0x6003) the PD configuration its Chk_Cfg chose, the control
 * and status words and the MOVILINK service in its parameter channel.
 *
 * Pure functions, no allocation: the text goes into the caller's buffers. The names come from
 * where the project already keeps them (rig_diag_text for the standard octets, the DFP21B's own
 * configuration check and P090 text, the MOVIDRIVE word texts, replay's parameter channel
 * text), so the monitor names things as the log and the replay report do. */
#ifndef MONITOR_MON_DECODE_H
#define MONITOR_MON_DECODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "monitor/monitor.h"

#define MON_DECODE_TEXT 192u

/* "Station_Not_Ready Prm_Req | no master, ident 0x6003" and, after ", ext: ", each extended
 * diagnosis block by its header, separated by "; ". dpv1: the slave was parameterised in DP-V1
 * mode (mon_prm_dpv1), so a device-related block is a DP-V1 alarm or status block. out is
 * always terminated; returns its length. */
size_t mon_decode_diag(const uint8_t *d, size_t len, bool dpv1, char *out, size_t max);

/* The Set_Prm DU switches DP-V1 on (DPV1_Status_1 bit 7). */
bool mon_prm_dpv1(const uint8_t *prm, size_t len);

/* The DFP21B's view of a slave's last Chk_Cfg and Data_Exchange octets. */
typedef struct mon_dfp21b {
    bool cfg_valid;        /* the card accepts this configuration */
    bool param_channel;    /* the 8-octet MOVILINK channel leads the I/O */
    uint8_t pd_words;      /* 0 when the configuration is not valid */
    char pd_config[24];    /* as P090 shows it: "3PD + PARAM", "0PD" */
    bool has_control;      /* the outputs carry PO1 */
    uint16_t control_word;
    char control_text[MON_DECODE_TEXT]; /* "enable, no rapid stop, no stop" */
    bool has_status;       /* the inputs carry PI1 */
    uint16_t status_word;
    char status_text[MON_DECODE_TEXT];  /* "output stage enabled, ..., unit status 4 (enabled)" */
    char param_request[MON_DECODE_TEXT]; /* "" when the channel carries no service */
    char param_answer[MON_DECODE_TEXT];
} mon_dfp21b_t;

/* The station is a DP slave with ident 0x6003. */
bool mon_is_dfp21b(const mon_station_t *st);
/* Decodes cfg (the accepted Chk_Cfg DU), the last outputs and the last inputs. */
void mon_decode_dfp21b(const uint8_t *cfg, size_t cfg_len, const uint8_t *outputs,
                       size_t out_len, const uint8_t *inputs, size_t in_len, mon_dfp21b_t *r);
/* The same from a station's figures. */
void mon_decode_dfp21b_station(const mon_station_t *st, mon_dfp21b_t *r);

#endif
