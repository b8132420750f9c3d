/* The card and the master as stations on a host medium (sim_station_t). */
#ifndef SIM_STATIONS_STATIONS_H
#define SIM_STATIONS_STATIONS_H

#include "dfp21b/dfp21b.h"
#include "dp_master/dp_master.h"
#include "movidrive/movidrive.h"
#include "sim_hal/file_nvm.h"
#include "sim_hal/sim_board.h"
#include "sim_hal/sim_station.h"

typedef enum card_inverter {
    CARD_INVERTER_NONE = 0, /* no inverter: PI words echo PO words (loopback) */
    CARD_INVERTER_SIM,      /* the emulated MOVIDRIVE in this process */
    CARD_INVERTER_LINK,     /* an external ml_link (SBus over CAN) */
} card_inverter_t;

/* Room for any start-up note: both files with both images named, at the longest paths. */
#define CARD_NVM_NOTE_MAX 2560u

typedef struct card_station {
    dfp21b_t card;
    sim_leds_t leds;
    sim_dip_t dip;
    card_inverter_t inverter;
    movidrive_t md;
    movidrive_inproc_link_t movidrive_link;
    file_nvm_t nvm;      /* the inverter's EEPROM */
    file_nvm_t card_nvm; /* the card's own storage: I&M1..I&M4 */
    char nvm_note[CARD_NVM_NOTE_MAX]; /* card_station_init's note in full ("" = none) */
    /* Parameter services seen on their way to the inverter and back (card_options_t). */
    ml_link_t inverter_link; /* the link the card's requests are forwarded to */
    uint8_t last_request[ML_MAX_CHANNELS][ML_TELEGRAM_LEN];
    bool request_seen[ML_MAX_CHANNELS];
    void (*param_observer)(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                           const uint8_t rsp[ML_TELEGRAM_LEN]);
    void *param_observer_ctx;
} card_station_t;

typedef struct card_options {
    uint8_t address;     /* DIP switches */
    uint32_t fixed_baud; /* 0 = automatic */
    bool strict_timing;
    uint32_t baud_control_ms;
    card_inverter_t inverter;
    const char *eeprom_path;     /* CARD_INVERTER_SIM: EEPROM image file, NULL = none */
    uint32_t inverter_delay_us;  /* CARD_INVERTER_SIM: how long each parameter service takes */
    ml_link_t external_link;     /* CARD_INVERTER_LINK */
    const char *card_nvm_path;   /* the card's non-volatile storage file, NULL = none */
    const char *serial;          /* I&M0 serial number; NULL: "DFP-SIM-<address>" */
    void (*event)(void *ctx, const dp_event_t *ev);
    void (*led_change)(void *ctx, hal_led_id_t led, hal_led_mode_t mode);
    void *ctx;
    /* Optional: every parameter service the inverter (emulated or external) answered, with the
     * request as the card sent it on that link channel (movilink_link.h), when the answer
     * arrives. Outside the protocol core, so telemetry (LCM) sees services without the card
     * knowing; services the card answers itself (a malformed request, no inverter, a timeout)
     * never reach the link and are not reported. */
    void (*param_observer)(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                           const uint8_t rsp[ML_TELEGRAM_LEN]);
    void *param_observer_ctx;
} card_options_t;

sim_station_t card_station(card_station_t *c);
/* Call after attaching the station to a medium (which supplies uart). Returns 0 with err empty,
 * or -1 with a note in err: what the drive's EEPROM file or the card's NVM file did not give as
 * stored (file_nvm_open's text, naming the files and reasons, after "drive EEPROM: " or
 * "card NVM: ", parts joined by "; "): the previous image PATH.bak was used, or none was usable
 * and the drive starts from its factory settings (I&M1..I&M4 empty), or the path is not a
 * regular file and is neither read nor written. Never fatal: the card runs either way, so -1
 * means only that the note has something to say. A note with both files' images unusable
 * needs about 2 x (the paths' lengths + 250) octets: a shorter err gets it cut, c->nvm_note
 * keeps it whole. */
int card_station_init(card_station_t *c, const card_options_t *opt, hal_uart_t uart,
                      hal_time_us_t now, char *err, size_t errlen);
/* The card's end: gives up the locks on its EEPROM and NVM files (file_nvm_close), as the end
 * of the process would, so another card (or the same one, initialised anew) may open them. */
void card_station_close(card_station_t *c);
/* For links that deliver inverter answers (SBus): forwards to the card. */
void card_station_param_response(void *card_station, uint8_t channel,
                                 const uint8_t rsp[ML_TELEGRAM_LEN]);
void card_station_process_inputs(void *card_station, const uint16_t *pi, uint8_t n);

sim_station_t master_station(dp_master_t *m);

/* The DFP21B's 9 user-parameter octets (DP-V1 status 00 00 00, SEW block, diag alarm off). */
extern const uint8_t dfp21b_user_prm_default[9];

#endif
