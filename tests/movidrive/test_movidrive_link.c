/* movidrive_inproc_link: the card's inverter link in process. Responses arrive delay_us after the
 * request, never at once; PO go to the drive and fresh PI come back; the fieldbus status reaches
 * P819/P831. Also driven through the card's service client (movilink_client). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "movidrive_test_util.h"
#include "movilink/movilink_client.h"

static movidrive_t md;
static movidrive_inproc_link_t link_;
static ml_link_t ml;

static struct {
    int responses;
    uint8_t channel;
    uint8_t rsp[8];
    hal_time_us_t at;
    int inputs;
    uint16_t pi[ML_MAX_PD];
    uint8_t pi_n;
    int chain; /* requests to start from the completion */
} card;

static hal_time_us_t now;

static void on_response(void *c, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    CHECK(c == &card);
    card.responses++;
    card.channel = channel;
    memcpy(card.rsp, rsp, 8);
    card.at = now;
    if (card.chain > 0) {
        card.chain--;
        uint8_t req[8];
        movidrive_req(req, 0x01, MOVIDRIVE_IDX_P130_RAMP_UP, 0);
        CHECK_EQ(ml.ops->param_request(ml.ctx, channel, req), 0);
    }
}

static void on_inputs(void *c, const uint16_t *pi, uint8_t n)
{
    CHECK(c == &card);
    card.inputs++;
    memcpy(card.pi, pi, n * sizeof pi[0]);
    card.pi_n = n;
}

static void setup(uint32_t delay_us)
{
    movidrive_cfg_t cfg = {.eeprom = {0}, .terminal_enable = true};
    CHECK_EQ(movidrive_init(&md, &cfg, NULL, 0), 0);
    memset(&link_, 0, sizeof link_);
    memset(&card, 0, sizeof card);
    link_.md = &md;
    link_.param_response = on_response;
    link_.process_inputs = on_inputs;
    link_.card = &card;
    link_.delay_us = delay_us;
    ml = movidrive_inproc_link(&link_);
    now = 1000;
    movidrive_inproc_link_poll(&link_, now);
}

static void poll_to(hal_time_us_t t)
{
    now = t;
    movidrive_inproc_link_poll(&link_, now);
}

static void test_delay(void)
{
    setup(5000);
    uint8_t req[8];
    movidrive_req(req, 0x01, MOVIDRIVE_IDX_FIRMWARE, 0);
    CHECK_EQ(ml.ops->param_request(ml.ctx, 0, req), 0);
    CHECK_EQ(card.responses, 0); /* never answered inside the request */
    /* the next deadline the link asks for is the response */
    CHECK_EQ(movidrive_inproc_link_poll(&link_, now), 1000 + 5000);
    poll_to(5999);
    CHECK_EQ(card.responses, 0);
    poll_to(6000);
    CHECK_EQ(card.responses, 1);
    CHECK_EQ(card.at, 6000);
    CHECK_EQ(card.channel, 0);
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    poll_to(20000);
    CHECK_EQ(card.responses, 1); /* once */

    /* two channels in parallel, each with its own due time */
    movidrive_req(req, 0x32, MOVIDRIVE_IDX_P130_RAMP_UP, 3000);
    CHECK_EQ(ml.ops->param_request(ml.ctx, 1, req), 0);
    poll_to(22000);
    movidrive_req(req, 0x01, MOVIDRIVE_IDX_P130_RAMP_UP, 0);
    CHECK_EQ(ml.ops->param_request(ml.ctx, 2, req), 0);
    /* one request per channel at a time */
    CHECK_EQ(ml.ops->param_request(ml.ctx, 2, req), -1);
    CHECK_EQ(ml.ops->param_request(ml.ctx, ML_MAX_CHANNELS, req), -1);
    poll_to(25000);
    CHECK_EQ(card.responses, 2);
    CHECK_EQ(card.channel, 1);
    CHECK_BYTES(card.rsp, 8, 0x32, 0x00, 0x21, 0x16, 0x00, 0x00, 0x0B, 0xB8);
    poll_to(26999);
    CHECK_EQ(card.responses, 2);
    poll_to(27000);
    CHECK_EQ(card.responses, 3);
    CHECK_EQ(card.channel, 2);
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x21, 0x16, 0x00, 0x00, 0x0B, 0xB8);
    /* errors travel the same way */
    movidrive_req(req, 0x32, MOVIDRIVE_IDX_FIRMWARE, 0);
    CHECK_EQ(ml.ops->param_request(ml.ctx, 3, req), 0);
    poll_to(32000);
    CHECK_BYTES(card.rsp, 8, 0xB2, 0x00, 0x20, 0x6C, 0x08, 0x00, 0x00, 0x12);

    /* a completion that starts the next request on the same channel */
    card.chain = 1;
    movidrive_req(req, 0x01, MOVIDRIVE_IDX_FIRMWARE, 0);
    CHECK_EQ(ml.ops->param_request(ml.ctx, 0, req), 0);
    poll_to(37000);
    CHECK_EQ(card.responses, 5);
    CHECK_EQ(movidrive_inproc_link_poll(&link_, now), 42000);
    poll_to(42000);
    CHECK_EQ(card.responses, 6);
    CHECK_BYTES(card.rsp, 8, 0x01, 0x00, 0x21, 0x16, 0x00, 0x00, 0x0B, 0xB8);

    /* delay 0: delivered at the next poll, still not inside the request */
    setup(0);
    movidrive_req(req, 0x01, MOVIDRIVE_IDX_FIRMWARE, 0);
    CHECK_EQ(ml.ops->param_request(ml.ctx, 0, req), 0);
    CHECK_EQ(card.responses, 0);
    poll_to(now);
    CHECK_EQ(card.responses, 1);
}

static void test_process_data(void)
{
    setup(1000);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE, 3, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE, 2, 1), 0);
    const uint16_t po[3] = {0x0006, 1500, 0};
    ml.ops->process_outputs(ml.ctx, po, 3);
    CHECK_EQ(card.inputs, 1); /* PI pushed right away */
    CHECK_EQ(card.pi_n, 3);
    CHECK_EQ(card.pi[0], 0x0407);
    CHECK_EQ(card.pi[1], 0);
    /* the ramp runs on the link's polls; fresh PI with each */
    for (int i = 0; i < 100; i++) {
        poll_to(now + 1000);
    }
    CHECK(card.inputs > 100);
    CHECK_EQ(card.pi[1], 750); /* 150 rpm after 100 ms */
    CHECK_EQ(md.speed_actual_mrpm, 150000);
    /* fieldbus status: P819, and the timeout reaction */
    ml_fieldbus_status_t st = {.pd_config = 4, .pd_words = 3, .param_channel = true,
                               .baud = 12000000, .address = 7, .watchdog_ms = 60, .prm_count = 1,
                               .data_exchange = true};
    ml.ops->fieldbus_status(ml.ctx, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 60);
    CHECK_EQ(movidrive_read(&md, 8454), 7);
    st.timeout = true;
    ml.ops->fieldbus_status(ml.ctx, &st);
    poll_to(now + 1000);
    CHECK_EQ(card.pi[0], 0x1C25); /* F28, rapid stop running */
}

/* The card's service client over the in-process link: a response is accepted after delay_us,
 * and a delay longer than the client's timeout ends in class 6 code 2. */
static struct {
    int done;
    uint8_t rsp[8];
} client_done;

static void done_cb(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    (void)channel;
    client_done.done++;
    memcpy(client_done.rsp, rsp, 8);
}

static void client_response(void *c, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    ml_client_response(c, channel, rsp);
}

static void test_with_client(void)
{
    static ml_client_t client;
    setup(3000);
    link_.param_response = client_response;
    link_.card = &client;
    ml_client_init(&client, ml, 200000);
    memset(&client_done, 0, sizeof client_done);
    uint8_t req[8];
    movidrive_req(req, 0x41, MOVIDRIVE_IDX_P160_N11, 0); /* handshake set: the client clears it */
    CHECK_EQ(ml_client_request(&client, 0, req, done_cb, NULL, now), 0);
    CHECK(ml_client_busy(&client, 0));
    poll_to(now + 2999);
    ml_client_poll(&client, now);
    CHECK_EQ(client_done.done, 0);
    poll_to(now + 1);
    CHECK_EQ(client_done.done, 1);
    CHECK_BYTES(client_done.rsp, 8, 0x01, 0x00, 0x21, 0x29, 0x00, 0x02, 0x49, 0xF0);

    /* slower than the client's patience: 6/2 from the card, the late answer dropped */
    link_.delay_us = 300000;
    movidrive_req(req, 0x01, MOVIDRIVE_IDX_FIRMWARE, 0);
    CHECK_EQ(ml_client_request(&client, 0, req, done_cb, NULL, now), 0);
    hal_time_us_t start = now;
    poll_to(start + 200000);
    ml_client_poll(&client, now);
    CHECK_EQ(client_done.done, 2);
    CHECK_BYTES(client_done.rsp, 8, 0x81, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    poll_to(start + 300000);
    CHECK_EQ(client_done.done, 2);
    CHECK_EQ(client.stale_responses, 1);
}

int main(void)
{
    RUN_TEST(test_delay);
    RUN_TEST(test_process_data);
    RUN_TEST(test_with_client);
    return check_report();
}
