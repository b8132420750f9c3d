/* Target card: the whole DFP21B (dfp21b + dp_slave + DP-V1 + MOVILINK) on a simulated line,
 * with the emulated MOVIDRIVE in process or a fake inverter link the input drives, fed
 * sequences of telegrams: well-formed ones with fuzzed fields (FDL status, Slave_Diag, Set_Prm,
 * Chk_Cfg, Data_Exchange with the parameter channel, Global_Control, Get_Cfg/Rd_Inp/Rd_Outp,
 * other SAPs, DP-V1 class 1 and class 2), raw telegrams, mutated telegrams and garbage with
 * UART error flags, from several masters, to the card, to others and to everybody, with
 * retries, short idle times and time passing (watchdog, baud control, inverter timeouts).
 *
 * Input: config octet (bit 0 relaxed timing, bits 1..3 rate, bit 4 emulated MOVIDRIVE, bits
 * 5..6 inverter delay), address octet (>= 0xF0: DIP value octet & 0x7F, else 4), a 32-bit
 * start time, then operations (op octet: low 4 bits the kind, bits 4..5 addressing: 0/1 the
 * card, 2 broadcast, 3 another station; bit 6 SDN instead of SRD; bit 7 repeat the FCB (a
 * retry) or, for kind 0, a short idle time before the telegram):
 *   0 raw telegram (u8 length, octets)  1 FDL status  2 Slave_Diag  3 Set_Prm  4 Chk_Cfg
 *   5 Data_Exchange  6 Global_Control  7 other DP SAPs  8 DP-V1 class 1  9 DP-V1 class 2
 *   10 garbage with error flags  11 a telegram of kind u8 with one octet changed
 *   12 time passes  13 the fake inverter answers  14 master address changes  15 nothing
 *
 * Properties (abort on violation):
 *  - the card transmits only in the receive path, right after the last octet of a telegram
 *    that fdl_rx (fed the same characters) accepted, at most once per telegram, never when it
 *    is off the bus;
 *  - that telegram is a request addressed to the card's own address (never broadcast, never
 *    another station), had TSYN idle before it (strict timing), and is not SDN;
 *  - the reply is not sent before end of request + 11 bit times; it re-assembles, parses and
 *    re-encodes to itself; DA = the requester, SA = the card, a response FC (OK, RS, DL, DH),
 *    SAPs swapped exactly when the request had SAPs and the reply carries data or DL;
 *  - DP state changes only along Wait_Prm -> Wait_Cfg -> Data_Exch, Wait_Cfg -> Wait_Prm,
 *    Data_Exch -> Wait_Prm / Wait_Cfg, with the old state the last one reported; Wait_Cfg only
 *    by a Set_Prm, Data_Exch only by a Chk_Cfg, Wait_Prm by a telegram or the watchdog;
 *  - the outputs the card holds (outside Sync mode) are zeros or the data of the last
 *    Data_Exchange it executed;
 *  - known finding (FUZZ_KNOWN=sdn_services): a state change, and new outputs, only by an SRD
 *    addressed to the card itself (not by SDN, not by a broadcast);
 *  - every valid request for the card (SRD, FDL status) after TSYN idle gets a reply; known
 *    finding (FUZZ_KNOWN=tsyn_wrap): also after an idle line of 4.29 s or more; known finding
 *    (FUZZ_KNOWN=srd_gc): also an SRD to the Global_Control SAP;
 *  - the cyclic channel starts at most one service per handshake edge the master makes in the
 *    Data_Exchange telegrams the card executes, counted from the entry into Data_Exch (plus
 *    one for the entry); known finding (FUZZ_KNOWN=channel_reentry): across entries too. */
#include "dfp21b/dfp21b.h"
#include "dp_slave/dp_wire.h"
#include "dpv1/dpv1_wire.h"
#include "fuzz_link.h"
#include "movidrive/movidrive.h"

typedef struct rig {
    dfp21b_t card;
    movidrive_t md;
    movidrive_inproc_link_t movidrive_link;
    bool use_md;
    fake_link_t link;
    fdl_rx_t shadow;
    bool strict;
    uint32_t baud;
    uint32_t char_ns;
    uint8_t address;
    uint8_t dip;
    bool on_bus;
    hal_time_us_t t0;
    uint64_t t_ns;
    /* receive path bookkeeping */
    bool in_rx;
    bool frame_now;         /* the shadow receiver completed a telegram on this character */
    bool transmitted;       /* during this telegram */
    uint32_t transmits;
    /* the telegram being processed (valid while frame_now) */
    fdl_msg_t req;
    bool req_ok;
    bool req_addressed;     /* addressed to the card itself */
    bool req_srd;           /* ... as SRD (a service with reply) */
    bool fcb_repeat;
    uint8_t tx_frame[FDL_FRAME_MAX]; /* the reply, checked once the telegram is done */
    size_t tx_len;
    bool last_accepted;
    bool tsyn_drop;         /* the card dropped this telegram for want of TSYN idle */     /* the last character completed a telegram (shadow) */
    bool wd_expired;
    /* DP state model */
    dp_state_t state;
    /* outputs model */
    uint8_t last_dx[DP_MAX_IO_LEN];
    uint8_t last_dx_len;
    bool have_dx;
    /* cyclic channel */
    uint32_t ch0_requests;
    uint8_t master_hs;
    uint32_t master_toggles;
    uint32_t ch0_base;      /* ch0_requests and master_toggles when Data_Exch was entered */
    uint32_t toggles_base;
    /* masters */
    uint8_t master;
    bool fcb[128];
    bool fcb_first[128];
    uint8_t c2_sap;
    uint8_t last_reply[128][FDL_FRAME_MAX];
    uint16_t last_len[128];
} rig_t;

static rig_t r;
static bool known_sdn_services;
static bool known_tsyn_wrap;
static bool known_srd_gc;
static bool known_channel_reentry;

static hal_time_us_t now_us(void) { return (hal_time_us_t)(r.t0 + (hal_time_us_t)(r.t_ns / 1000u)); }

/* ---- the card's UART ------------------------------------------------------------------------ */

static int uart_set_baud(void *ctx, uint32_t baud)
{
    (void)ctx;
    PROPERTY(baud == r.baud, "a fixed-rate card switched to %u", baud);
    return 0;
}

static int uart_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    (void)ctx;
    if (fz_trace_on()) fz_hex("  card ->", frame, len);
    PROPERTY(r.on_bus, "a card off the bus (DIP %u) transmitted", r.dip);
    PROPERTY(r.in_rx, "a transmit outside the receive path (from a poll)");
    PROPERTY(r.frame_now, "a transmit on a character that completed no telegram");
    PROPERTY(!r.transmitted, "a second transmit for one telegram");
    r.transmitted = true;
    r.transmits++;
    PROPERTY(r.req_ok, "a reply to a telegram that does not parse");
    const fdl_msg_t *q = &r.req;
    PROPERTY((q->fc & FDL_FC_REQUEST) != 0u, "a reply to a response (FC %02X)", q->fc);
    PROPERTY(q->da != FDL_ADDR_BROADCAST, "a reply to a broadcast");
    PROPERTY(q->da == r.address, "a reply to a telegram for station %u (card %u)", q->da,
             r.address);
    uint8_t code = (uint8_t)(q->fc & FDL_FC_CODE_MASK);
    PROPERTY(code != FDL_REQ_SDN_LOW && code != FDL_REQ_SDN_HIGH, "a reply to SDN");
    if (r.strict) {
        PROPERTY(r.shadow.idle_before_ns == UINT32_MAX ||
                     (uint64_t)r.shadow.idle_before_ns + FDL_RX_GAP_TOLERANCE_NS >=
                         (uint64_t)FDL_TSYN_BITS * r.char_ns / FDL_CHAR_BITS,
                 "a reply to a request with only %u ns idle before it", r.shadow.idle_before_ns);
    }
    hal_time_us_t min_start = r.shadow.frame_end_t + hal_uart_bits_us(r.baud, FDL_MIN_TSDR_DEFAULT_BITS);
    PROPERTY(hal_time_diff(not_before, min_start) >= 0, "reply %d us before end + min TSDR",
             hal_time_diff(min_start, not_before));
    PROPERTY(len <= sizeof r.tx_frame, "a reply of %zu octets", len);
    memcpy(r.tx_frame, frame, len);
    r.tx_len = len;
    return 0;
}

/* What the reply says, checked once the card is done with the telegram: an FCB repeat is
 * reported after the reply went out (the reply does not wait for the event). */
static void check_reply(void)
{
    const fdl_msg_t *q = &r.req;
    const uint8_t *frame = r.tx_frame;
    size_t len = r.tx_len;
    uint8_t code = (uint8_t)(q->fc & FDL_FC_CODE_MASK);
    bool srd = code == FDL_REQ_SRD_LOW || code == FDL_REQ_SRD_HIGH;
    if (r.fcb_repeat) {
        /* a retry: the previous answer to this master again, whatever the request says */
        PROPERTY(srd && len == r.last_len[q->sa] && memcmp(frame, r.last_reply[q->sa], len) == 0,
                 "a retry of master %u not answered with its previous reply", q->sa);
    } else if (srd) {
        memcpy(r.last_reply[q->sa], frame, len);
        r.last_len[q->sa] = (uint16_t)len;
    }
    bool sc;
    fdl_msg_t m;
    if (!fz_check_reply(frame, len, r.baud, &sc, &m)) {
        PROPERTY(code == FDL_REQ_SRD_LOW || code == FDL_REQ_SRD_HIGH, "SC to FC %02X", q->fc);
        return;
    }
    PROPERTY(m.da == q->sa && m.sa == r.address, "reply DA %u SA %u to a request from %u", m.da,
             m.sa, q->sa);
    uint8_t rc = (uint8_t)(m.fc & FDL_FC_CODE_MASK);
    PROPERTY((m.fc & 0xF0u) == 0u && (rc == FDL_RSP_OK || rc == FDL_RSP_RS || rc == FDL_RSP_DL ||
                                      rc == FDL_RSP_DH),
             "reply FC %02X", m.fc);
    if (code == FDL_REQ_FDL_STATUS) {
        PROPERTY(rc == FDL_RSP_OK && len == FDL_SD1_LEN, "FDL status answered %02X", m.fc);
    }
    if (m.has_dsap && !r.fcb_repeat) {
        PROPERTY(q->has_dsap && q->has_ssap && m.dsap == q->ssap && m.ssap == q->dsap &&
                     rc == FDL_RSP_DL,
                 "reply SAPs %u/%u FC %02X to a request %u/%u", m.dsap, m.ssap, m.fc, q->dsap,
                 q->ssap);
    }
}

static const hal_uart_ops_t uart_ops = {.set_baud = uart_set_baud, .transmit = uart_transmit};

static uint8_t dip_read(void *ctx) { (void)ctx; return r.dip; }
static const hal_dip_ops_t dip_ops = {.read = dip_read};

/* ---- DP events ------------------------------------------------------------------------------ */

static void on_event(void *ctx, const dp_event_t *ev)
{
    (void)ctx;
    if (ev->type != DP_EV_STATE) {
        TRACE("  event %d value %u master %u\n", (int)ev->type, ev->value, ev->master);
    }
    if (ev->type == DP_EV_RX_ERROR && ev->value == FDL_RX_ERR_TSYN) {
        r.tsyn_drop = true;
    }
    if (ev->type == DP_EV_FCB_REPEAT) {
        r.fcb_repeat = true;
    }
    if (ev->type == DP_EV_WD_EXPIRED) {
        PROPERTY(!r.in_rx, "watchdog expiry in the receive path");
        r.wd_expired = true;
    }
    if (ev->type != DP_EV_STATE) {
        return;
    }
    TRACE("  state %s -> %s\n", dp_state_name(ev->old_state), dp_state_name(ev->new_state));
    PROPERTY(ev->old_state == r.state, "state change from %s, last reported %s",
             dp_state_name(ev->old_state), dp_state_name(r.state));
    dp_state_t o = ev->old_state;
    dp_state_t n = ev->new_state;
    bool edge = (o == DP_STATE_WAIT_PRM && n == DP_STATE_WAIT_CFG) ||
                (o == DP_STATE_WAIT_CFG && n == DP_STATE_DATA_EXCH) ||
                (o == DP_STATE_WAIT_CFG && n == DP_STATE_WAIT_PRM) ||
                (o == DP_STATE_DATA_EXCH && n == DP_STATE_WAIT_PRM) ||
                (o == DP_STATE_DATA_EXCH && n == DP_STATE_WAIT_CFG);
    PROPERTY(edge, "no such edge: %s -> %s", dp_state_name(o), dp_state_name(n));
    if (n == DP_STATE_WAIT_PRM) {
        PROPERTY(r.frame_now || r.wd_expired, "Wait_Prm without a telegram or watchdog expiry");
    } else {
        PROPERTY(r.in_rx && r.frame_now && r.req_ok && r.req.has_dsap &&
                     r.req.dsap == (n == DP_STATE_WAIT_CFG ? DP_SAP_SET_PRM : DP_SAP_CHK_CFG),
                 "%s without a %s telegram", dp_state_name(n),
                 n == DP_STATE_WAIT_CFG ? "Set_Prm" : "Chk_Cfg");
    }
    if (n == DP_STATE_DATA_EXCH) {
        r.ch0_base = r.ch0_requests;
        r.toggles_base = r.master_toggles;
    }
    if (r.in_rx && known_sdn_services) {
        PROPERTY(r.req_addressed && r.req_srd, "%s -> %s by a telegram to station %u (FC %02X)",
                 dp_state_name(o), dp_state_name(n), r.req.da, r.req.fc);
    }
    r.state = n;
}

/* ---- the inverter link (counting channel 0 on the way) ------------------------------------ */

static int shim_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    (void)ctx;
    if (channel == DFP21B_CH_CYCLIC) {
        r.ch0_requests++;
        TRACE("  cyclic service %u: %02X index %u\n", r.ch0_requests, req[0], ml_index(req));
        if (known_channel_reentry) {
            PROPERTY(r.ch0_requests <= r.master_toggles, "cyclic service %u for %u handshake "
                     "edges of the master", r.ch0_requests, r.master_toggles);
        } else {
            /* Within one stay in Data_Exch; the entry itself may count as one edge (the
             * channel restarts from handshake 0: the known finding). */
            PROPERTY(r.ch0_requests - r.ch0_base <= r.master_toggles - r.toggles_base + 1u,
                     "%u cyclic services for %u handshake edges since entering Data_Exch",
                     r.ch0_requests - r.ch0_base, r.master_toggles - r.toggles_base);
        }
    }
    if (r.use_md) {
        ml_link_t l = movidrive_inproc_link(&r.movidrive_link);
        return l.ops->param_request(l.ctx, channel, req);
    }
    return fl_param_request(&r.link, channel, req);
}

static void shim_process_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    (void)ctx;
    if (r.use_md) {
        ml_link_t l = movidrive_inproc_link(&r.movidrive_link);
        l.ops->process_outputs(l.ctx, po, n);
    } else {
        fl_process_outputs(&r.link, po, n);
    }
}

static void shim_fieldbus_status(void *ctx, const ml_fieldbus_status_t *st)
{
    (void)ctx;
    if (r.use_md) {
        ml_link_t l = movidrive_inproc_link(&r.movidrive_link);
        l.ops->fieldbus_status(l.ctx, st);
    } else {
        fl_fieldbus_status(&r.link, st);
    }
}

static const ml_link_ops_t shim_ops = {.param_request = shim_param_request,
                                       .process_outputs = shim_process_outputs,
                                       .fieldbus_status = shim_fieldbus_status};

static void card_param_response(void *card, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    dfp21b_inverter_param_response(card, channel, rsp);
}

static void card_process_inputs(void *card, const uint16_t *pi, uint8_t n)
{
    dfp21b_inverter_process_inputs(card, pi, n);
}

/* ---- the line ------------------------------------------------------------------------------- */

static hal_time_us_t earlier(hal_time_us_t a, hal_time_us_t b) { return hal_time_diff(a, b) < 0 ? a : b; }

/* The card's main loop as the simulator runs it (sim_host/sim_stations/src/stations.c). */
static hal_time_us_t card_poll(void)
{
    hal_time_us_t now = now_us();
    r.wd_expired = false;
    (void)fdl_rx_poll(&r.shadow, now); /* the card's receiver forgets the line as this one does */
    hal_time_us_t next;
    if (r.use_md) {
        next = movidrive_inproc_link_poll(&r.movidrive_link, now);
        next = earlier(next, movidrive_tick(&r.md, now));
        next = earlier(next, dfp21b_poll(&r.card, now));
        next = earlier(next, movidrive_inproc_link_poll(&r.movidrive_link, now));
        if (r.card.inputs_dirty) {
            next = earlier(next, dfp21b_poll(&r.card, now));
        }
    } else {
        next = dfp21b_poll(&r.card, now);
    }
    r.wd_expired = false;
    return next;
}

static void check_outputs(void)
{
    const dp_slave_t *s = &r.card.dp;
    if (s->sync_mode || s->out_len == 0u) {
        return;
    }
    static const uint8_t zeros[DP_MAX_IO_LEN];
    bool ok = memcmp(s->outputs, zeros, s->out_len) == 0 ||
              (r.have_dx && r.last_dx_len == s->out_len &&
               memcmp(s->outputs, r.last_dx, s->out_len) == 0);
    if (!ok) {
        fz_hex("outputs", s->outputs, s->out_len);
        fz_hex("last DX", r.last_dx, r.last_dx_len);
    }
    PROPERTY(ok, "the card's outputs are neither cleared nor the last Data_Exchange's");
}

static void deliver_char(uint8_t byte, uint8_t flags, uint64_t dt_ns)
{
    r.t_ns += dt_ns;
    hal_time_us_t t = now_us();
    fdl_rx_result_t sr = fdl_rx_char(&r.shadow, byte, flags, t);
    r.frame_now = sr == FDL_RX_FRAME;
    r.transmitted = false;
    r.fcb_repeat = false;
    r.tsyn_drop = false;
    r.req_ok = false;
    r.req_addressed = false;
    dp_state_t state_before = r.card.dp.state;
    uint8_t master_before = r.card.dp.master_add;
    if (r.frame_now) {
        r.req_ok = fz_parse_checked(r.shadow.buf, r.shadow.frame_len, &r.req) == FDL_PARSE_OK;
        r.req_addressed = r.req_ok && r.req.da == r.address;
        uint8_t c = (uint8_t)(r.req.fc & FDL_FC_CODE_MASK);
        r.req_srd = r.req_ok && (c == FDL_REQ_SRD_LOW || c == FDL_REQ_SRD_HIGH);
    }
    r.in_rx = true;
    dfp21b_rx_char(&r.card, byte, flags, t);
    r.in_rx = false;
    if (!r.frame_now) {
        PROPERTY(!r.transmitted, "transmitted without a telegram");
        return;
    }
    if (r.transmitted) {
        check_reply();
    }
    r.frame_now = false;
    /* A Data_Exchange the card executed: remember its outputs and the handshake edge. */
    const fdl_msg_t *q = &r.req;
    uint8_t code = (uint8_t)(q->fc & FDL_FC_CODE_MASK);
    /* SDN and broadcast Data_Exchange are executed too (known finding sdn_services): unless
     * that property is asked for, they count as executed. */
    bool sdn = code == FDL_REQ_SDN_LOW || code == FDL_REQ_SDN_HIGH;
    r.last_accepted = true;
    bool counts = (r.req_addressed && r.req_srd && r.transmitted) ||
                  (!known_sdn_services && sdn && (r.req_addressed || q->da == FDL_ADDR_BROADCAST));
    if (r.req_ok && counts && !r.tsyn_drop && (q->fc & FDL_FC_REQUEST) != 0u && !q->has_dsap &&
        !r.fcb_repeat && state_before == DP_STATE_DATA_EXCH &&
        r.card.dp.state == DP_STATE_DATA_EXCH && master_before == q->sa &&
        q->data_len == r.card.dp.out_len && q->data_len > 0u) {
        memcpy(r.last_dx, q->data, q->data_len);
        r.last_dx_len = q->data_len;
        r.have_dx = true;
        if (r.card.pd.param_channel) {
            uint8_t hs = (uint8_t)(q->data[0] & ML_MGMT_HANDSHAKE);
            if (hs != r.master_hs) {
                r.master_toggles++;
            }
            r.master_hs = hs;
        }
    }
    check_outputs();
}

static void send_frame(const uint8_t *frame, size_t len, bool short_idle)
{
    if (len == 0u) return;
    if (fz_trace_on()) {
        TRACE("t=%u ", now_us());
        fz_hex("-> card", frame, len);
    }
    uint64_t idle = short_idle ? 5ull * r.char_ns / FDL_CHAR_BITS
                               : (r.strict ? 40ull * r.char_ns / FDL_CHAR_BITS : 1500000ull);
    uint32_t before = r.transmits;
    r.last_accepted = false;
    for (size_t k = 0; k < len; k++) {
        r.last_accepted = false;
        deliver_char(frame[k], 0, (k == 0u ? idle : 0u) + r.char_ns);
    }
    /* Every valid request for the card that it may answer is answered: SRD and FDL status,
     * after TSYN idle (strict timing). */
    uint8_t code = (uint8_t)(r.req.fc & FDL_FC_CODE_MASK);
    if (r.last_accepted && r.req_ok && r.on_bus && r.req.da == r.address &&
        (r.req.fc & FDL_FC_REQUEST) != 0u &&
        (code == FDL_REQ_SRD_LOW || code == FDL_REQ_SRD_HIGH || code == FDL_REQ_FDL_STATUS) &&
        !short_idle) {
        /* fdl_rx clamps the idle time to UINT32_MAX - 1 ns (4.29 s) */
        bool long_pause = r.shadow.idle_before_ns >= UINT32_MAX - 1u - FDL_RX_GAP_TOLERANCE_NS &&
                          r.shadow.idle_before_ns != UINT32_MAX;
        bool gc = r.req.has_dsap && r.req.dsap == DP_SAP_GLOBAL_CONTROL &&
                  code != FDL_REQ_FDL_STATUS;
        if ((!long_pause || known_tsyn_wrap) && (!gc || known_srd_gc)) {
            PROPERTY(r.transmits != before, "a valid request for the card (FC %02X, %u ns idle "
                     "before it) was not answered", r.req.fc, r.shadow.idle_before_ns);
        }
    }
    if (r.transmits != before) {
        r.t_ns += 200ull * r.char_ns; /* the reply goes out; the master listens */
    }
    (void)card_poll(); /* the medium polls a station right after a telegram */
    check_outputs();
}

static void advance(uint64_t dt_us)
{
    uint64_t end = r.t_ns + dt_us * 1000u;
    for (int k = 0; k < 64; k++) {
        hal_time_us_t next = card_poll();
        int32_t d = hal_time_diff(next, now_us());
        uint64_t at = r.t_ns + (d > 0 ? (uint64_t)d * 1000u : 1000u);
        if (at > end) break;
        r.t_ns = at;
    }
    r.t_ns = end;
    (void)card_poll();
    check_outputs();
}

/* ---- telegram builders ---------------------------------------------------------------------- */

static uint8_t fc_for(uint8_t op, uint8_t sa, bool srd)
{
    bool repeat = (op & 0x80u) != 0u;
    if (!srd || (op & 0x40u) != 0u) {
        return 0x46u; /* SDN high */
    }
    if (!repeat) {
        if (r.fcb_first[sa]) {
            r.fcb[sa] = !r.fcb[sa];
        } else {
            r.fcb_first[sa] = true;
            r.fcb[sa] = true;
            return 0x40u | 0x20u | FDL_REQ_SRD_HIGH; /* FCV=0 FCB=1 */
        }
    }
    return (uint8_t)(0x40u | FDL_FC_FCV | (r.fcb[sa] ? FDL_FC_FCB : 0u) | FDL_REQ_SRD_HIGH);
}

static uint8_t da_for(uint8_t op)
{
    switch ((op >> 4) & 3u) {
    case 2: return FDL_ADDR_BROADCAST;
    case 3: return (uint8_t)((r.address + 1u) & 0x7Fu);
    default: return r.address;
    }
}

static size_t build(fz_t *f, uint8_t op, uint8_t *out)
{
    uint8_t sa = r.master;
    uint8_t da = da_for(op);
    uint8_t du[FDL_DU_MAX];
    switch (op & 15u) {
    case 0: {
        size_t n = (size_t)fz_u8(f) % FDL_FRAME_MAX + 1u;
        fz_bytes(f, out, n);
        return n;
    }
    case 1:
        return fdl_encode(out, da, sa, 0x49, false, 0, 0, NULL, 0);
    case 2:
        return fdl_encode(out, da, sa, fc_for(op, sa, true), true, DP_SAP_SLAVE_DIAG,
                          DP_SAP_MASTER, NULL, 0);
    case 3: {
        uint8_t sel = fz_u8(f);
        static const uint8_t statuses[4] = {0x88, 0xB8, 0x80, 0xC8};
        du[0] = (sel & 0x80u) != 0u ? fz_u8(f) : statuses[sel & 3u];
        du[1] = (sel & 0x40u) != 0u ? fz_u8(f) : (uint8_t)(1u + (sel >> 2) % 4u);
        du[2] = (sel & 0x40u) != 0u ? fz_u8(f) : (uint8_t)(2u + (sel >> 4) % 50u);
        du[3] = 0x0B;
        du[4] = 0x60;
        du[5] = (sel & 0x20u) != 0u ? fz_u8(f) : 0x03;
        du[6] = fz_u8(f);
        static const uint8_t user[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
        memcpy(&du[7], user, sizeof user);
        uint8_t v = fz_u8(f);
        du[7] = (uint8_t)(v & 0x87u);     /* DPV1_Enable, WD base, start/stop control */
        du[15] = (uint8_t)((v >> 3) & 1u); /* diag alarm on/off */
        size_t n = 16;
        if ((v & 0x10u) != 0u) {          /* mutate one user octet */
            du[7u + fz_u8(f) % 9u] = fz_u8(f);
        }
        if ((v & 0x20u) != 0u) {
            n = (size_t)fz_u8(f) % 40u;
            fz_bytes(f, &du[16], n > 16u ? n - 16u : 0u);
        }
        return fdl_encode(out, da, sa, fc_for(op, sa, true), true, DP_SAP_SET_PRM, DP_SAP_MASTER,
                          du, n);
    }
    case 4: {
        static const uint8_t cfgs[][3] = {{2, 0xF3, 0xF2}, {1, 0xF2, 0}, {2, 0xF3, 0xF1},
                                          {2, 0xF3, 0xF5}, {1, 0xF0, 0}, {2, 0x00, 0xF9},
                                          {2, 0xB7, 0xF2}, {3, 0xF3, 0xE2}};
        uint8_t sel = fz_u8(f);
        size_t n;
        if ((sel & 0x80u) != 0u) {
            n = (size_t)fz_u8(f) % 8u + 1u;
            fz_bytes(f, du, n);
        } else {
            const uint8_t *c = cfgs[sel % 8u];
            n = c[0];
            if (n == 3u) { du[0] = 0xF3; du[1] = 0xE2; du[2] = 0xD2; }
            else memcpy(du, &c[1], n);
        }
        return fdl_encode(out, da, sa, fc_for(op, sa, true), true, DP_SAP_CHK_CFG, DP_SAP_MASTER,
                          du, n);
    }
    case 5: {
        uint8_t sel = fz_u8(f);
        size_t n = r.card.dp.out_len;
        if ((sel & 0xC0u) == 0xC0u) n = fz_u8(f) % 40u;
        if (n > sizeof du) n = sizeof du;
        fz_bytes(f, du, n);
        if (n >= 8u && (sel & 0x01u) != 0u) { /* a well-behaved parameter request */
            du[0] = (uint8_t)((r.master_hs ^ ((sel & 0x02u) != 0u ? ML_MGMT_HANDSHAKE : 0u)) |
                              0x30u | (1u + (sel >> 2) % 3u));
            du[1] = 0;
            du[2] = (uint8_t)(0x20u + (sel >> 4) % 0x0Cu);
        }
        if (n == 0u && (sel & 0x20u) == 0u) {
            return fdl_encode(out, da, sa, fc_for(op, sa, true), false, 0, 0, NULL, 0);
        }
        return fdl_encode(out, da, sa, fc_for(op, sa, true), false, 0, 0, du, n);
    }
    case 6: {
        du[0] = fz_u8(f);
        du[1] = fz_u8(f);
        if ((du[0] & 0x80u) == 0u) du[0] &= 0x3Eu;
        return fdl_encode(out, (op & 0x30u) == 0u ? FDL_ADDR_BROADCAST : da, sa, 0x46, true,
                          DP_SAP_GLOBAL_CONTROL, DP_SAP_MASTER, du, 2);
    }
    case 7: {
        static const uint8_t saps[5] = {DP_SAP_GET_CFG, DP_SAP_RD_INP, DP_SAP_RD_OUTP,
                                        DP_SAP_SET_SLAVE_ADD, 20};
        uint8_t sel = fz_u8(f);
        uint8_t dsap = sel >= 0xF0u ? (uint8_t)(sel & 0x3Fu) : saps[sel % 5u];
        size_t n = dsap == DP_SAP_SET_SLAVE_ADD ? 4u : 0u;
        fz_bytes(f, du, n);
        return fdl_encode(out, da, sa, fc_for(op, sa, true), true, dsap, DP_SAP_MASTER, du, n);
    }
    case 8:
    case 9: {
        bool c1 = (op & 15u) == 8u;
        uint8_t kind = fz_u8(f);
        size_t n = 0;
        uint8_t dsap = c1 ? DPV1_SAP_C1 : r.c2_sap;
        uint8_t ssap = c1 ? DPV1_SAP_C1 : 50u;
        switch (kind % 6u) {
        case 0: /* Write 47: read P076 or write an IPOS variable */
            du[0] = DPV1_FN_WRITE; du[1] = 0; du[2] = 47;
            if ((kind & 0x80u) != 0u) {
                uint8_t q[] = {fz_u8(f), 0x40, 0x00, 0x01, 0x30, 0x00, 0x2A, 0xF8, 0, 0,
                               0x43, 0x01, fz_u8(f), fz_u8(f), fz_u8(f), fz_u8(f)};
                memcpy(&du[4], q, sizeof q);
                n = 4u + sizeof q;
            } else {
                uint8_t q[] = {fz_u8(f), (uint8_t[]){1, 0x40}[kind >> 6 & 1u], 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0, 0};
                memcpy(&du[4], q, sizeof q);
                n = 4u + sizeof q;
            }
            du[3] = (uint8_t)(n - 4u);
            break;
        case 1:
            du[0] = DPV1_FN_READ; du[1] = 0; du[2] = (kind & 0x80u) != 0u ? 255u : 47u; du[3] = 240;
            n = 4;
            break;
        case 2: /* raw PDU */
            n = (size_t)fz_u8(f) % 60u;
            fz_bytes(f, du, n);
            break;
        case 3: /* C2: Initiate via the RM, or Abort */
            if (!c1) {
                uint16_t to = (uint16_t)(1u + fz_u8(f));
                const uint8_t ini[20] = {0x57, 0, 0, 0, (uint8_t)(to >> 8), (uint8_t)to, 1, 0, 0, 0,
                                         0, 0, 0, 2, 0, 2, 0, 0, 0, 0};
                memcpy(du, ini, sizeof ini);
                n = sizeof ini;
                dsap = DPV1_SAP_RM;
            } else {
                n = 0;
            }
            break;
        case 4:
            du[0] = (kind & 0x80u) != 0u ? DPV1_FN_ABORT : DPV1_FN_IDLE;
            du[1] = 0; du[2] = 0x23; du[3] = 0;
            n = 4;
            break;
        default: /* poll */
            n = 0;
            break;
        }
        if (!c1 && (kind & 0x40u) != 0u) r.c2_sap = (uint8_t)(r.c2_sap ^ 1u);
        return fdl_encode(out, da, sa, fc_for(op, sa, true), true, dsap, ssap, du, n);
    }
    default:
        return 0;
    }
}

/* ---- the target ----------------------------------------------------------------------------- */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static bool once;
    if (!once) {
        known_sdn_services = fz_known("sdn_services");
        known_tsyn_wrap = fz_known("tsyn_wrap");
        known_srd_gc = fz_known("srd_gc");
        known_channel_reentry = fz_known("channel_reentry");
        once = true;
    }
    fz_t f = {data, size, 0};
    memset(&r, 0, sizeof r);
    uint8_t cfgb = fz_u8(&f);
    uint8_t addrb = fz_u8(&f);
    r.strict = (cfgb & 1u) == 0u;
    r.baud = hal_uart_bauds[((cfgb >> 1) & 7u) % HAL_UART_NUM_BAUDS];
    r.char_ns = hal_uart_char_ns(r.baud);
    r.use_md = (cfgb & 0x10u) != 0u;
    r.dip = addrb >= 0xF0u ? (uint8_t)(fz_u8(&f) & 0x7Fu) : 4u;
    r.address = r.dip;
    r.on_bus = r.dip <= DFP21B_MAX_ADDRESS;
    r.t0 = fz_u32(&f);
    r.master = 2;
    r.state = DP_STATE_WAIT_PRM;
    r.link.deliver = card_param_response;
    r.link.deliver_ctx = &r.card;
    ml_link_t link = {.ops = &shim_ops, .ctx = NULL};
    if (r.use_md) {
        movidrive_cfg_t mcfg = {.terminal_enable = true};
        char err[128];
        PROPERTY(movidrive_init(&r.md, &mcfg, err, sizeof err) == 0, "movidrive_init: %s", err);
        static const uint32_t delays[4] = {0, 3000, 50000, 300000};
        r.movidrive_link = (movidrive_inproc_link_t){
            .md = &r.md, .param_response = card_param_response,
            .process_inputs = card_process_inputs, .card = &r.card,
            .delay_us = delays[(cfgb >> 5) & 3u]};
    }
    dfp21b_cfg_t cfg = {
        .uart = {.ops = &uart_ops, .ctx = NULL},
        .dip = {.ops = &dip_ops, .ctx = NULL},
        .fixed_baud = r.baud,
        .strict_timing = r.strict,
        .inverter = link,
        .serial = "FUZZ",
        .software_revision = {1, 2, 3},
        .event = on_event,
    };
    fdl_rx_init(&r.shadow, r.baud, r.strict);
    dfp21b_init(&r.card, &cfg, now_us());
    (void)card_poll();

    while (fz_more(&f)) {
        uint8_t op = fz_u8(&f);
        uint8_t kind = (uint8_t)(op & 15u);
        TRACE("op %u (%02X)\n", kind, op);
        uint8_t frame[FDL_FRAME_MAX];
        switch (kind) {
        case 10: { /* garbage with error flags */
            size_t n = (size_t)fz_u8(&f) % 32u + 1u;
            for (size_t k = 0; k < n; k++) {
                uint8_t b = fz_u8(&f);
                uint8_t fl = fz_u8(&f);
                deliver_char(b, (uint8_t)((fl & 0xF8u) == 0u ? fl & 7u : 0u),
                             r.char_ns + ((fl & 0x80u) != 0u ? 1000ull * (fl & 0x7Fu) : 0u));
            }
            (void)card_poll();
            break;
        }
        case 11: { /* a telegram with one octet changed */
            uint8_t sub = (uint8_t)((fz_u8(&f) % 9u) + 1u);
            size_t n = build(&f, (uint8_t)((op & 0xF0u) | sub), frame);
            if (n == 0u) break;
            frame[fz_u8(&f) % n] ^= (uint8_t)(fz_u8(&f) | 1u);
            send_frame(frame, n, false);
            break;
        }
        case 12:
            advance((uint64_t)fz_u16(&f) << ((op >> 4) & 7u));
            break;
        case 13:
            if (!r.use_md) {
                (void)fl_answer(&r.link, &f, fz_u8(&f), (uint8_t)((op >> 4) & 3u), (op & 0x40u) != 0u);
                (void)card_poll();
            }
            break;
        case 14:
            r.master = (uint8_t)(fz_u8(&f) % 126u);
            break;
        case 15:
            break;
        default: {
            size_t n = build(&f, op, frame);
            send_frame(frame, n, kind == 0u && (op & 0x80u) != 0u);
            break;
        }
        }
    }
    return 0;
}
