/* SBus on SocketCAN through the tty runner: the card side as dfp-sim slave uses it
 * (sim_host/can/src/inverter_can.c) against an inverter on another socket of the same interface.
 *
 *   test_sbus_socketcan                          spec parsing and open errors (any host)
 *   test_sbus_socketcan --can vcan0              + round trips against an in-process
 *                                                  sbus_inverter_t on its own socket (in the VM)
 *   test_sbus_socketcan --can vcan0 --external A + round trips against another program, e.g.
 *                                                  `dfp-sim inverter --can vcan0 --sbus-address A`
 *                                                  (the emulated MOVIDRIVE: checks P076 and H0;
 *                                                  --write-h1/--expect-h1/--expect-h0 check the
 *                                                  EEPROM across a restart of that program)
 */
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "can/inverter_can.h"
#include "movilink/movilink_client.h"

#define MOVIDRIVE_P100_FIELDBUS 3u /* setpoint source (index 8461) */
#define MOVIDRIVE_P101_FIELDBUS 2u /* control signal source (index 8462) */

static const char *ifname;
static int external_address = -1;
static long write_h1 = -1;  /* --write-h1 N: non-volatile write of H1 (index 11001) */
static long expect_h1 = -1; /* --expect-h1 N: H1 must read N (after a restart: from EEPROM) */
static long expect_h0 = -1; /* --expect-h0 N: H0 must read N before this run writes it */
static bool drive_test;     /* --drive: P100/P101 = FIELDBUS, enable, ramp, PO stop */

/* ---- the card side: a service client on the inverter_can link ------------------------------ */

static struct {
    inverter_can_t inv;
    ml_client_t client;
    tty_runner_t runner;
    uint16_t pi[3];
    uint8_t n_pi;
    int pi_frames;
    uint8_t rsp[ML_TELEGRAM_LEN];
    int done;
    volatile int stop;
} card;

static void card_param_response(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    ml_client_response(&card.client, channel, rsp);
}

static void card_process_inputs(void *ctx, const uint16_t *pi, uint8_t n)
{
    (void)ctx;
    memcpy(card.pi, pi, n * sizeof pi[0]);
    card.n_pi = n;
    card.pi_frames++;
    card.stop = 1;
}

static void on_done(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    (void)channel;
    memcpy(card.rsp, rsp, ML_TELEGRAM_LEN);
    card.done++;
    card.stop = 1;
}

static hal_time_us_t client_timer(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    return ml_client_poll(&card.client, now);
}

/* One service, run until it completes (or 2 s). */
static bool service(const uint8_t req[ML_TELEGRAM_LEN], uint8_t channel)
{
    int before = card.done;
    card.stop = 0;
    if (ml_client_request(&card.client, channel, req, on_done, NULL, tty_now_us()) != 0) {
        return false;
    }
    tty_runner_wake(&card.runner); /* the client's deadline is new (the link woke it too) */
    if (card.done == before &&
        tty_runner_run_until(&card.runner, tty_now_us() + 2000000u, &card.stop) != 0) {
        fprintf(stderr, "runner: %s\n", tty_runner_error(&card.runner));
    }
    return card.done == before + 1;
}

static bool exchange_pd(const uint16_t po[3])
{
    int before = card.pi_frames;
    card.stop = 0;
    ml_link_t l = inverter_can_link(&card.inv);
    l.ops->process_outputs(l.ctx, po, 3);
    (void)tty_runner_run_until(&card.runner, tty_now_us() + 2000000u, &card.stop);
    return card.pi_frames == before + 1;
}

/* ---- an in-process inverter on its own socket --------------------------------------------- */

static struct {
    socketcan_t sock;
    sbus_inverter_t inv;
    int32_t h0;
    uint16_t po[3];
    int params;
} drive;

static void drive_rx(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    sbus_inverter_rx(&drive.inv, f, tty_now_us());
}

static void drive_param(void *ctx, const uint8_t req[ML_TELEGRAM_LEN], uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    drive.params++;
    uint8_t svc = req[0] & ML_MGMT_SERVICE_MASK;
    if (ml_index(req) == 8300u && svc == ML_SVC_READ) {
        ml_put_data(rsp, 0x311C7289u);
    } else if (ml_index(req) == 11000u && svc == ML_SVC_READ) {
        ml_put_data(rsp, (uint32_t)drive.h0);
    } else if (ml_index(req) == 11000u && svc == ML_SVC_WRITE_VOLATILE) {
        drive.h0 = (int32_t)ml_data(req);
    } else {
        ml_put_error(rsp, ML_CLASS_OTHER, 0, ML_ADD_ILLEGAL_INDEX);
    }
}

static void drive_po(void *ctx, const uint16_t *po, uint8_t n)
{
    (void)ctx;
    memcpy(drive.po, po, n * sizeof po[0]);
}

static void drive_pi(void *ctx, uint16_t *pi, uint8_t n)
{
    (void)ctx;
    (void)n;
    pi[0] = (uint16_t)(drive.po[0] == 6u ? 0x0007u : 0x0002u);
    pi[1] = drive.po[1];
    pi[2] = 0x0BB8;
}

/* ---- tests --------------------------------------------------------------------------------- */

static void test_parse(void)
{
    char name[32];
    uint8_t a = 99;
    char err[160] = "";
    CHECK_EQ(inverter_can_parse("can:vcan0", name, sizeof name, &a, err, sizeof err), 0);
    CHECK_STR(name, "vcan0");
    CHECK_EQ(a, 0);
    CHECK_EQ(inverter_can_parse("can:can1:33", name, sizeof name, &a, err, sizeof err), 0);
    CHECK_STR(name, "can1");
    CHECK_EQ(a, 33);
    CHECK_EQ(inverter_can_parse("vcan0:63", name, sizeof name, &a, err, sizeof err), 0);
    CHECK_EQ(a, 63);
    CHECK_EQ(inverter_can_parse("can:vcan0:64", name, sizeof name, &a, err, sizeof err), -1);
    CHECK_STR(err, "--inverter can:vcan0:64: SBus address must be 0..63");
    CHECK_EQ(inverter_can_parse("can:vcan0:x", name, sizeof name, &a, err, sizeof err), -1);
    CHECK_EQ(inverter_can_parse("can:vcan0:", name, sizeof name, &a, err, sizeof err), -1);
    CHECK_EQ(inverter_can_parse("can:", name, sizeof name, &a, err, sizeof err), -1);
    CHECK_STR(err, "--inverter can:: expected can:IFACE[:ADDR], e.g. can:vcan0:1");
}

static void test_open_error(void)
{
    tty_runner_t r;
    tty_runner_init(&r);
    inverter_can_t l;
    char err[256] = "";
    CHECK_EQ(inverter_can_open(&l, "can:nosuchcan0:1", card_param_response, card_process_inputs,
                               NULL, &r, err, sizeof err),
             -1);
    CHECK(strncmp(err, "cannot open CAN interface nosuchcan0: ", 38) == 0);
    CHECK_EQ(r.num_fds, 0);
    CHECK_EQ(r.num_timers, 0);
    printf("open error: %s\n", err);
}

static bool open_card(uint8_t address)
{
    char err[256] = "";
    char spec[64];
    memset(&card, 0, sizeof card);
    tty_runner_init(&card.runner);
    (void)snprintf(spec, sizeof spec, "can:%s:%u", ifname, (unsigned)address);
    if (inverter_can_open(&card.inv, spec, card_param_response, card_process_inputs, NULL,
                          &card.runner, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return false;
    }
    ml_client_init(&card.client, inverter_can_link(&card.inv), 200000u);
    return tty_runner_add_timer(&card.runner, client_timer, NULL) == 0;
}

static const uint8_t read_fw[8] = {0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 0};

static void test_round_trips_in_process(void)
{
    char err[256] = "";
    CHECK(open_card(1));
    memset(&drive, 0, sizeof drive);
    CHECK_EQ(socketcan_open(&drive.sock, ifname, drive_rx, NULL, err, sizeof err), 0);
    CHECK_EQ(socketcan_attach(&drive.sock, &card.runner), 0); /* same thread, same loop */
    sbus_inverter_cfg_t ic = {.can = socketcan_can(&drive.sock), .address = 1, .param = drive_param,
                              .process_outputs = drive_po, .process_inputs = drive_pi};
    sbus_inverter_init(&drive.inv, &ic);

    CHECK(service(read_fw, 0));
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    const uint8_t wv[8] = {0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8};
    CHECK(service(wv, 1));
    CHECK_EQ(drive.h0, 3000);
    const uint8_t rd[8] = {0x01, 0x00, 0x2A, 0xF8, 0, 0, 0, 0};
    CHECK(service(rd, 3));
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);
    const uint16_t po[3] = {6, 1500, 0};
    CHECK(exchange_pd(po));
    CHECK_EQ(card.n_pi, 3);
    CHECK_EQ(card.pi[0], 7);
    CHECK_EQ(card.pi[1], 1500);
    CHECK_EQ(card.pi[2], 3000);
    /* 100 services back to back: each answered, none lost, in well under a second each. */
    hal_time_us_t t0 = tty_now_us();
    int ok = 0;
    for (uint32_t i = 0; i < 100u; i++) {
        uint8_t w[8] = {0x33, 0x00, 0x2A, 0xF8, 0, 0, (uint8_t)(i >> 8), (uint8_t)i};
        ok += service(w, (uint8_t)(i % 4u)) && (card.rsp[0] & ML_MGMT_ERROR) == 0u &&
              drive.h0 == (int32_t)i;
    }
    int32_t us = hal_time_diff(tty_now_us(), t0);
    CHECK_EQ(ok, 100);
    printf("100 parameter services over %s: %.0f us each\n", ifname, us / 100.0);
    /* The inverter gone: the client answers 6/2 after its deadline. */
    socketcan_close(&drive.sock);
    CHECK(service(read_fw, 0));
    CHECK_BYTES(card.rsp, 8, 0x81, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(card.client.timeouts, 1);
    /* The link holds the SBus channel while a late answer may still come (the client's wait
     * and its quarantine), then its own deadline runs although nothing arrived. */
    CHECK_EQ(card.inv.link.timeouts, 0);
    (void)tty_runner_run_until(&card.runner, tty_now_us() + ML_RESPONSE_TIMEOUT_US + 50000u, NULL);
    CHECK_EQ(card.inv.link.timeouts, 1);
    inverter_can_close(&card.inv);
    CHECK_EQ(card.runner.num_fds, 0);
    CHECK_EQ(card.runner.num_timers, 1); /* the client's own timer stays */
}

/* Keep sending PO every 10 ms for ms milliseconds, as the card does every DP cycle. */
static void pd_for(const uint16_t po[3], int ms)
{
    for (int t = 0; t < ms; t += 10) {
        (void)exchange_pd(po);
        (void)tty_runner_run_until(&card.runner, tty_now_us() + 10000u, NULL);
    }
}

/* The drive over SBus: sources to FIELDBUS, enable with 300 rpm, the actual speed ramps up;
 * PO frames stop (a DP timeout on the card) and the drive's SBus timeout reacts (F28 here, see
 * cmd_inverter.c); a reset edge in control word bit 6 clears it. */
static void test_drive_external(void)
{
    /* P100 first: both need controller inhibit, which P101 = FIELDBUS with an enabling
     * control word would end. */
    uint8_t w2[8] = {0x33, 0x00, 0x21, 0x0D, 0, 0, 0, MOVIDRIVE_P100_FIELDBUS};
    CHECK(service(w2, 0));
    CHECK_EQ(card.rsp[0], 0x33);
    uint8_t w[8] = {0x33, 0x00, 0x21, 0x0E, 0, 0, 0, MOVIDRIVE_P101_FIELDBUS};
    CHECK(service(w, 0));
    CHECK_EQ(card.rsp[0], 0x33);
    const uint16_t run[3] = {0x0006, 1500, 0}; /* enable, 1500 x 0.2 rpm = 300 rpm */
    pd_for(run, 300);
    CHECK((card.pi[0] & 0x0001u) != 0u); /* output stage enabled */
    CHECK((card.pi[0] & 0x0004u) != 0u); /* PO data enabled */
    CHECK((card.pi[0] & 0x0020u) == 0u);
    CHECK(card.pi[1] > 0u && card.pi[1] <= 1500u); /* ramping up (PI2 = speed, 0.2 rpm) */
    printf("drive after 300 ms: PI1 %04X, speed %.1f rpm\n", card.pi[0], card.pi[1] * 0.2);
    /* No PO for 300 ms: more than P815 (100 ms by default). */
    (void)tty_runner_run_until(&card.runner, tty_now_us() + 300000u, NULL);
    pd_for(run, 50);
    CHECK((card.pi[0] & 0x0020u) != 0u); /* fault latched */
    CHECK_EQ(card.pi[0] >> 8, 28);          /* F28 in the high byte */
    printf("after a PO gap: PI1 %04X (fault F%u)\n", card.pi[0], card.pi[0] >> 8);
    const uint16_t reset[3] = {0x0046, 0, 0};
    pd_for(reset, 50);
    const uint16_t stop[3] = {0x0000, 0, 0};
    pd_for(stop, 50);
    CHECK((card.pi[0] & 0x0020u) == 0u); /* reset on the bit 6 edge */
}

/* Against the emulated MOVIDRIVE in another process (dfp-sim inverter). */
static void test_round_trips_external(void)
{
    CHECK(open_card((uint8_t)external_address));
    CHECK(service(read_fw, 0));
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    const uint8_t rd_h1[8] = {0x01, 0x00, 0x2A, 0xF9, 0, 0, 0, 0};
    if (expect_h0 >= 0) {
        const uint8_t rd_h0[8] = {0x01, 0x00, 0x2A, 0xF8, 0, 0, 0, 0};
        CHECK(service(rd_h0, 2));
        CHECK_EQ(card.rsp[0], 0x01);
        CHECK_EQ(ml_data(card.rsp), (uint32_t)expect_h0);
    }
    if (expect_h1 >= 0) {
        CHECK(service(rd_h1, 2));
        CHECK_EQ(card.rsp[0], 0x01);
        CHECK_EQ(ml_data(card.rsp), (uint32_t)expect_h1);
    }
    if (write_h1 >= 0) {
        uint8_t w[8] = {0x32, 0x00, 0x2A, 0xF9, 0, 0, 0, 0};
        ml_put_data(w, (uint32_t)write_h1);
        CHECK(service(w, 1));
        CHECK_EQ(card.rsp[0], 0x32);
        CHECK(service(rd_h1, 0));
        CHECK_EQ(ml_data(card.rsp), (uint32_t)write_h1);
    }
    const uint8_t wv[8] = {0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8}; /* H0 = 3000 */
    CHECK(service(wv, 1));
    CHECK_BYTES(card.rsp, 8, 0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);
    const uint8_t rd[8] = {0x01, 0x00, 0x2A, 0xF8, 0, 0, 0, 0};
    CHECK(service(rd, 3));
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);
    const uint8_t bad[8] = {0x01, 0x00, 0x00, 0x07, 0, 0, 0, 0}; /* index 7: none */
    CHECK(service(bad, 0));
    CHECK_EQ(card.rsp[0], 0x81);
    CHECK_EQ(card.rsp[4], ML_CLASS_OTHER);
    CHECK_EQ(card.rsp[7], ML_ADD_ILLEGAL_INDEX);
    const uint16_t po[3] = {0x0006, 1500, 0};
    CHECK(exchange_pd(po));
    CHECK_EQ(card.n_pi, 3);
    printf("external inverter at SBus address %d: PI %04X %04X %04X\n", external_address,
           card.pi[0], card.pi[1], card.pi[2]);
    if (drive_test) {
        test_drive_external();
    }
    inverter_can_close(&card.inv);
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--can") == 0 && i + 1 < argc) {
            ifname = argv[++i];
        } else if (strcmp(argv[i], "--external") == 0 && i + 1 < argc) {
            external_address = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--write-h1") == 0 && i + 1 < argc) {
            write_h1 = atol(argv[++i]);
        } else if (strcmp(argv[i], "--expect-h1") == 0 && i + 1 < argc) {
            expect_h1 = atol(argv[++i]);
        } else if (strcmp(argv[i], "--drive") == 0) {
            drive_test = true;
        } else if (strcmp(argv[i], "--expect-h0") == 0 && i + 1 < argc) {
            expect_h0 = atol(argv[++i]);
        } else {
            fprintf(stderr, "usage: %s [--can IFACE [--external ADDR [--expect-h0 N] "
                            "[--expect-h1 N] [--write-h1 N]]]\n", argv[0]);
            return 2;
        }
    }
    RUN_TEST(test_parse);
    RUN_TEST(test_open_error);
    if (ifname != NULL && external_address < 0) {
        RUN_TEST(test_round_trips_in_process);
    }
    if (ifname != NULL && external_address >= 0) {
        RUN_TEST(test_round_trips_external);
    }
    return check_report();
}
