/* The cyclic 8-byte channel and the service client, against a fake inverter link: exact octets
 * of every reply, exactly-once execution on the handshake edge, card-side errors, timeouts. */
#include <string.h>

#include "check.h"
#include "movilink/movilink_channel.h"
#include "movilink/movilink_client.h"

typedef struct fake_link {
    unsigned requests;
    uint8_t channel;
    uint8_t last[ML_TELEGRAM_LEN];
    int refuse;
} fake_link_t;

static int fake_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    fake_link_t *f = ctx;
    if (f->refuse) {
        return -1;
    }
    f->requests++;
    f->channel = channel;
    memcpy(f->last, req, ML_TELEGRAM_LEN);
    return 0;
}

static const ml_link_ops_t fake_ops = {.param_request = fake_param_request};

static fake_link_t link_;
static ml_client_t client;
static ml_channel_t chan;

static void setup(void)
{
    memset(&link_, 0, sizeof link_);
    ml_client_init(&client, (ml_link_t){.ops = &fake_ops, .ctx = &link_}, 100000u);
    ml_channel_init(&chan, &client, 0);
}

#define REQ(...) ((const uint8_t[ML_TELEGRAM_LEN]){__VA_ARGS__})
#define REPLY_IS(...) CHECK_BYTES(ml_channel_reply(&chan), ML_TELEGRAM_LEN, __VA_ARGS__)

static void test_starts_with_zero_reply_and_no_service(void)
{
    setup();
    REPLY_IS(0, 0, 0, 0, 0, 0, 0, 0);
    /* Handshake 0 equals the initial reply: no edge, nothing runs. */
    ml_channel_request(&chan, REQ(0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    CHECK_EQ(link_.requests, 0);
    CHECK_EQ(chan.services, 0);
    REPLY_IS(0, 0, 0, 0, 0, 0, 0, 0);
}

static void test_read_runs_once_on_the_edge(void)
{
    setup();
    for (int i = 0; i < 10; i++) {
        ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), (hal_time_us_t)i * 1000u);
    }
    CHECK_EQ(link_.requests, 1);
    /* Towards the inverter the handshake bit is cleared (it would mean SBus synchronous). */
    CHECK_BYTES(link_.last, 8, 0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 0);
    REPLY_IS(0, 0, 0, 0, 0, 0, 0, 0); /* still the previous reply while the service runs */
    ml_client_response(&client, 0, REQ(0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89));
    REPLY_IS(0x41, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    for (int i = 0; i < 10; i++) {
        ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 20000u);
    }
    CHECK_EQ(link_.requests, 1);
    CHECK_EQ(chan.services, 1);
}

static void test_write_and_inverter_error(void)
{
    setup();
    /* Write 4 octets (0x32) with handshake 1: index 8489 = 300000. */
    ml_channel_request(&chan, REQ(0x72, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0), 0);
    CHECK_BYTES(link_.last, 8, 0x32, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0);
    ml_client_response(&client, 0, REQ(0x32, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0));
    REPLY_IS(0x72, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0);
    /* Next write (handshake 0) answered by the inverter with class 8, value too high (0x15). */
    ml_channel_request(&chan, REQ(0x32, 0x00, 0x21, 0x29, 0x7F, 0xFF, 0xFF, 0xFF), 1000);
    CHECK_EQ(link_.requests, 2);
    ml_client_response(&client, 0, REQ(0xB2, 0x00, 0x21, 0x29, 0x08, 0x00, 0x00, 0x15));
    REPLY_IS(0xB2, 0x00, 0x21, 0x29, 0x08, 0x00, 0x00, 0x15);
}

static void test_card_errors_without_asking_the_inverter(void)
{
    setup();
    /* Reserved octet not 0: class 5 code 5. */
    ml_channel_request(&chan, REQ(0x41, 0x01, 0x20, 0x6C, 0, 0, 0, 0), 0);
    REPLY_IS(0xC1, 0x01, 0x20, 0x6C, 0x05, 0x05, 0x00, 0x00);
    /* Service 9: class 5 code 5. */
    ml_channel_request(&chan, REQ(0x09, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    REPLY_IS(0x89, 0x00, 0x20, 0x6C, 0x05, 0x05, 0x00, 0x00);
    /* Write with data length 2 octets (bits 5..4 = 01): class 6 code 8. */
    ml_channel_request(&chan, REQ(0x52, 0x00, 0x21, 0x29, 0, 0, 0x01, 0x00), 0);
    REPLY_IS(0xD2, 0x00, 0x21, 0x29, 0x06, 0x08, 0x00, 0x00);
    /* Read with a short length is fine: the length is ignored for reads. */
    ml_channel_request(&chan, REQ(0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    CHECK_EQ(link_.requests, 1);
    CHECK_EQ(chan.services, 4);
}

static void test_no_service_acknowledges_the_handshake(void)
{
    setup();
    ml_channel_request(&chan, REQ(0x40, 0x00, 0x12, 0x34, 1, 2, 3, 4), 0);
    REPLY_IS(0x40, 0x00, 0x12, 0x34, 1, 2, 3, 4);
    CHECK_EQ(link_.requests, 0);
}

static void test_timeout_gives_class_6_code_2_and_late_answer_is_dropped(void)
{
    setup();
    ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 1000);
    CHECK_EQ(ml_client_poll(&client, 50000), 101000u); /* next deadline: 1000 + 100000 */
    REPLY_IS(0, 0, 0, 0, 0, 0, 0, 0);
    ml_client_poll(&client, 101000);
    REPLY_IS(0xC1, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(client.timeouts, 1);
    ml_client_response(&client, 0, REQ(0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89));
    REPLY_IS(0xC1, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(client.stale_responses, 1);
}

static void test_link_down_answers_at_once(void)
{
    setup();
    link_.refuse = 1;
    ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    REPLY_IS(0xC1, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    CHECK(!ml_client_busy(&client, 0));
}

static void test_response_for_another_request_is_ignored(void)
{
    setup();
    ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    ml_client_response(&client, 0, REQ(0x01, 0x00, 0x20, 0x6D, 9, 9, 9, 9)); /* other index */
    ml_client_response(&client, 0, REQ(0x02, 0x00, 0x20, 0x6C, 9, 9, 9, 9)); /* other service */
    REPLY_IS(0, 0, 0, 0, 0, 0, 0, 0);
    CHECK_EQ(client.stale_responses, 2);
    ml_client_response(&client, 0, REQ(0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 7));
    REPLY_IS(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 7);
}

static void test_handshake_toggled_back_while_busy(void)
{
    setup();
    ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    /* The master gives up and toggles again with a new job while the first still runs. */
    ml_channel_request(&chan, REQ(0x01, 0x00, 0x20, 0x7E, 0, 0, 0, 0), 0);
    CHECK_EQ(link_.requests, 1);
    ml_client_response(&client, 0, REQ(0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 1));
    REPLY_IS(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 1);
    /* Now handshake 0 differs from the completed 1: the second job runs, once. */
    ml_channel_request(&chan, REQ(0x01, 0x00, 0x20, 0x7E, 0, 0, 0, 0), 0);
    ml_channel_request(&chan, REQ(0x01, 0x00, 0x20, 0x7E, 0, 0, 0, 0), 0);
    CHECK_EQ(link_.requests, 2);
    CHECK_BYTES(link_.last, 8, 0x01, 0x00, 0x20, 0x7E, 0, 0, 0, 0);
}

static void test_channels_are_independent(void)
{
    setup();
    CHECK_EQ(ml_client_request(&client, 1, REQ(0x01, 0, 0x20, 0x6C, 0, 0, 0, 0), NULL, NULL, 0), 0);
    CHECK_EQ(ml_client_request(&client, 1, REQ(0x01, 0, 0x20, 0x6C, 0, 0, 0, 0), NULL, NULL, 0), -1);
    CHECK_EQ(ml_client_request(&client, ML_MAX_CHANNELS, REQ(0x01, 0, 0, 0, 0, 0, 0, 0), NULL,
                               NULL, 0), -1);
    ml_channel_request(&chan, REQ(0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0), 0);
    CHECK_EQ(link_.channel, 0);
    CHECK(ml_client_busy(&client, 0));
    CHECK(ml_client_busy(&client, 1));
}

int main(void)
{
    RUN_TEST(test_starts_with_zero_reply_and_no_service);
    RUN_TEST(test_read_runs_once_on_the_edge);
    RUN_TEST(test_write_and_inverter_error);
    RUN_TEST(test_card_errors_without_asking_the_inverter);
    RUN_TEST(test_no_service_acknowledges_the_handshake);
    RUN_TEST(test_timeout_gives_class_6_code_2_and_late_answer_is_dropped);
    RUN_TEST(test_link_down_answers_at_once);
    RUN_TEST(test_response_for_another_request_is_ignored);
    RUN_TEST(test_handshake_toggled_back_while_busy);
    RUN_TEST(test_channels_are_independent);
    return check_report();
}
