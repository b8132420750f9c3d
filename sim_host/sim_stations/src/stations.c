#include "sim_stations/stations.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const uint8_t dfp21b_user_prm_default[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};

static void card_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    card_station_t *c = ctx;
    dfp21b_rx_char(&c->card, byte, flags, t);
}

static hal_time_us_t earlier(hal_time_us_t a, hal_time_us_t b)
{
    return hal_time_diff(a, b) < 0 ? a : b;
}

/* The card's main loop and, with the emulated inverter, the inverter's: the drive's time runs
 * to now under the old outputs before the card hands it new ones, and answers that became due
 * are delivered before the card builds its next input image. Only the image left at the end is
 * ever sent (a reply goes out from inside rx, never between these calls), so PI are pushed once
 * after the card's poll (pi_on_poll_only); the link pushes only words that changed, so the
 * card's second poll runs only when the image really changes. */
static hal_time_us_t card_poll(void *ctx, hal_time_us_t now)
{
    card_station_t *c = ctx;
    if (c->inverter != CARD_INVERTER_SIM) {
        return dfp21b_poll(&c->card, now);
    }
    hal_time_us_t next = movidrive_inproc_link_advance(&c->movidrive_link, now);
    next = earlier(next, dfp21b_poll(&c->card, now));
    /* PI for the PO just taken and for parameter writes the card's poll started */
    next = earlier(next, movidrive_inproc_link_poll(&c->movidrive_link, now));
    if (c->card.inputs_dirty) {
        next = earlier(next, dfp21b_poll(&c->card, now));
    }
    return next;
}

void card_station_param_response(void *card_station, uint8_t channel,
                                 const uint8_t rsp[ML_TELEGRAM_LEN])
{
    card_station_t *c = card_station;
    if (c->param_observer != NULL && channel < ML_MAX_CHANNELS && c->request_seen[channel]) {
        c->request_seen[channel] = false; /* a second answer to one request is not a service */
        c->param_observer(c->param_observer_ctx, channel, c->last_request[channel], rsp);
    }
    dfp21b_inverter_param_response(&c->card, channel, rsp);
}

/* The observed link: requests are remembered per channel on their way to the real link. */
static int observed_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    card_station_t *c = ctx;
    if (channel < ML_MAX_CHANNELS) {
        memcpy(c->last_request[channel], req, ML_TELEGRAM_LEN);
        c->request_seen[channel] = true;
    }
    return c->inverter_link.ops->param_request(c->inverter_link.ctx, channel, req);
}

static void observed_process_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    card_station_t *c = ctx;
    if (c->inverter_link.ops->process_outputs != NULL) {
        c->inverter_link.ops->process_outputs(c->inverter_link.ctx, po, n);
    }
}

static void observed_fieldbus_status(void *ctx, const ml_fieldbus_status_t *status)
{
    card_station_t *c = ctx;
    if (c->inverter_link.ops->fieldbus_status != NULL) {
        c->inverter_link.ops->fieldbus_status(c->inverter_link.ctx, status);
    }
}

static void observed_param_cancel(void *ctx, uint8_t channel)
{
    card_station_t *c = ctx;
    if (c->inverter_link.ops->param_cancel != NULL) {
        c->inverter_link.ops->param_cancel(c->inverter_link.ctx, channel);
    }
}

static const ml_link_ops_t observed_link_ops = {
    .param_request = observed_param_request,
    .process_outputs = observed_process_outputs,
    .fieldbus_status = observed_fieldbus_status,
    .param_cancel = observed_param_cancel,
};

void card_station_process_inputs(void *card_station, const uint16_t *pi, uint8_t n)
{
    card_station_t *c = card_station;
    dfp21b_inverter_process_inputs(&c->card, pi, n);
}

sim_station_t card_station(card_station_t *c)
{
    return (sim_station_t){.ctx = c, .rx_char = card_rx, .poll = card_poll};
}

/* Appends one part to the start-up note in err, "; " between parts. */
static void note_add(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void note_add(char *err, size_t errlen, const char *fmt, ...)
{
    size_t used = strlen(err);
    if (errlen == 0u || used + 1u >= errlen) {
        return;
    }
    if (used > 0u) {
        (void)snprintf(err + used, errlen - used, "; ");
        used = strlen(err);
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(err + used, errlen - used, fmt, ap);
    va_end(ap);
}

/* file_nvm_open's text names both images and both reasons: room for two paths. */
#define NVM_TEXT_MAX (2u * (FILE_NVM_PATH_MAX + 200u))

/* The emulated MOVIDRIVE, commissioned as the manual's §4.3 wiring leaves it: DI00 at +24 V.
 * What the EEPROM file or the drive had to say goes into the note in err: true if anything. */
static bool start_inverter(card_station_t *c, const card_options_t *opt, char *err,
                           size_t errlen)
{
    movidrive_cfg_t mcfg = {.terminal_enable = true};
    int nrc = 0;
    char nerr[NVM_TEXT_MAX] = "";
    if (opt->eeprom_path != NULL) {
        nrc = file_nvm_open(&c->nvm, opt->eeprom_path, movidrive_eeprom_size(), nerr,
                            sizeof nerr);
        mcfg.eeprom = file_nvm_hal(&c->nvm);
    }
    char merr[256] = "";
    int mrc = movidrive_init(&c->md, &mcfg, merr, sizeof merr);
    if (nrc < 0) {
        /* The drive can only add that it found nothing readable: the file's text says why. */
        note_add(err, errlen, "drive EEPROM: %s; the drive starts from its factory settings",
                 nerr);
    } else if (nrc > 0) {
        note_add(err, errlen, "drive EEPROM: %s", nerr);
    }
    if (nrc >= 0 && mrc != 0) {
        /* The file was read, its contents are not all the drive's: merr names no file. */
        note_add(err, errlen, "drive EEPROM: %s: %s",
                 opt->eeprom_path != NULL ? opt->eeprom_path : "(none)", merr);
    }
    c->movidrive_link = (movidrive_inproc_link_t){
        .md = &c->md, .param_response = card_station_param_response,
        .process_inputs = card_station_process_inputs, .card = c,
        .delay_us = opt->inverter_delay_us, .pi_on_poll_only = true};
    return nrc != 0 || mrc != 0;
}

/* The card's own storage (I&M1..I&M4); its note, if any, goes into err and sets *noted. */
static hal_nvm_t open_card_nvm(card_station_t *c, const char *path, char *err, size_t errlen,
                               bool *noted)
{
    if (path == NULL) {
        return (hal_nvm_t){0};
    }
    char nerr[NVM_TEXT_MAX] = "";
    int nrc = file_nvm_open(&c->card_nvm, path, IM_NVM_SIZE, nerr, sizeof nerr);
    if (nrc < 0) {
        note_add(err, errlen, "card NVM: %s; I&M1..I&M4 start empty", nerr);
    } else if (nrc > 0) {
        note_add(err, errlen, "card NVM: %s", nerr);
    }
    *noted = *noted || nrc != 0;
    return file_nvm_hal(&c->card_nvm);
}

void card_station_close(card_station_t *c)
{
    file_nvm_close(&c->nvm);
    file_nvm_close(&c->card_nvm);
}

int card_station_init(card_station_t *c, const card_options_t *opt, hal_uart_t uart,
                      hal_time_us_t now, char *err, size_t errlen)
{
    char *note = c->nvm_note;
    note[0] = '\0';
    bool noted = false;
    c->inverter = opt->inverter;
    ml_link_t link = {0};
    if (opt->inverter == CARD_INVERTER_SIM) {
        noted = start_inverter(c, opt, note, sizeof c->nvm_note);
        link = movidrive_inproc_link(&c->movidrive_link);
    } else if (opt->inverter == CARD_INVERTER_LINK) {
        link = opt->external_link;
    }
    c->param_observer = opt->param_observer;
    c->param_observer_ctx = opt->param_observer_ctx;
    memset(c->request_seen, 0, sizeof c->request_seen);
    if (opt->param_observer != NULL && link.ops != NULL) {
        c->inverter_link = link;
        link = (ml_link_t){.ops = &observed_link_ops, .ctx = c};
    }
    hal_nvm_t card_nvm = open_card_nvm(c, opt->card_nvm_path, note, sizeof c->nvm_note, &noted);
    if (err != NULL && errlen > 0u) {
        (void)snprintf(err, errlen, "%s", note);
    }
    static char default_serial[24];
    snprintf(default_serial, sizeof default_serial, "DFP-SIM-%03u", opt->address);
    memset(&c->leds, 0, sizeof c->leds);
    c->leds.on_change = opt->led_change;
    c->leds.ctx = opt->ctx;
    c->dip.switches = opt->address;
    dfp21b_cfg_t cfg = {
        .uart = uart,
        .led = sim_leds_hal(&c->leds),
        .dip = sim_dip_hal(&c->dip),
        .fixed_baud = opt->fixed_baud,
        .strict_timing = opt->strict_timing,
        .baud_control_ms = opt->baud_control_ms,
        .event = opt->event,
        .event_ctx = opt->ctx,
        .inverter = link,
        .nvm = card_nvm,
        .serial = opt->serial != NULL ? opt->serial : default_serial,
        .hardware_revision = 1,
        .software_revision = {0, 4, 0},
    };
    dfp21b_init(&c->card, &cfg, now);
    return noted ? -1 : 0;
}

static void master_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    dp_master_rx_char(ctx, byte, flags, t);
}

static hal_time_us_t master_poll(void *ctx, hal_time_us_t now)
{
    return dp_master_poll(ctx, now);
}

sim_station_t master_station(dp_master_t *m)
{
    return (sim_station_t){.ctx = m, .rx_char = master_rx, .poll = master_poll};
}
