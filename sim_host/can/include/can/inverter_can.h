/* The card's link to a MOVIDRIVE over SBus on SocketCAN, for `dfp-sim slave --inverter
 * can:IFACE[:ADDR]`.
 *
 *   inverter_can_t inv;
 *   tty_runner_init(&runner);                      // first: the link joins this runner
 *   if (inverter_can_open(&inv, "can:vcan0:1", on_param_response, on_process_inputs, card,
 *                         &runner, err, sizeof err) != 0) { cli_error("%s", err); ... }
 *   cfg.inverter = inverter_can_link(&inv);        // the ml_link_t for dfp21b_cfg_t.inverter
 *   ... tty_runner_run_until(&runner, ...) ...
 *   inverter_can_close(&inv);
 *
 * The link is sbus_card_link_t (movilink/sbus.h) on a SocketCAN socket: parameter requests go
 * out as 8·ADDR+512+3 frames, process outputs as 8·ADDR+3 (PO1..PO3); response and PI frames
 * from the inverter come back through the runner into param_response(card, channel, rsp) and
 * process_inputs(card, pi, 3), called from inside tty_runner_run_until() on its one thread (the
 * runner then polls every station at once, so the card sees them without delay). The link's
 * response deadline runs as a runner timer. ADDR is the inverter's SBus address P813, 0..63,
 * default 0 (the factory setting).
 *
 * Structs are caller-owned; nothing is allocated. */
#ifndef SIM_CAN_INVERTER_CAN_H
#define SIM_CAN_INVERTER_CAN_H

#include <stddef.h>
#include <stdint.h>

#include "movilink/movilink_link.h"
#include "movilink/sbus.h"
#include "sim_hal/socketcan.h"
#include "sim_hal/tty_port.h"

typedef struct inverter_can {
    socketcan_t sock;
    sbus_card_link_t link;
    tty_runner_t *runner;
    uint8_t address;
    char ifname[32];
} inverter_can_t;

/* Parse "can:IFACE[:ADDR]" (the "can:" prefix may be left out). Returns 0, or -1 with a reason
 * in err, e.g. "--inverter can:vcan0:64: SBus address must be 0..63". */
int inverter_can_parse(const char *spec, char *ifname, size_t ifname_len, uint8_t *address,
                       char *err, size_t errlen);
/* Open the interface, put the socket and the deadline timer into runner. Returns 0, or -1 with
 * one line in err (a bad spec, or socketcan_open()'s reason, e.g. "cannot open CAN interface
 * vcan0: Address family not supported by protocol (this kernel has no SocketCAN)"). */
int inverter_can_open(inverter_can_t *l, const char *spec,
                      void (*param_response)(void *card, uint8_t channel,
                                             const uint8_t rsp[ML_TELEGRAM_LEN]),
                      void (*process_inputs)(void *card, const uint16_t *pi, uint8_t n),
                      void *card, tty_runner_t *runner, char *err, size_t errlen);
ml_link_t inverter_can_link(inverter_can_t *l);
/* Leaves the runner and closes the socket. */
void inverter_can_close(inverter_can_t *l);

#endif
