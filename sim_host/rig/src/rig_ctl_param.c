#include "rig_ctl_param.h"

#include <stdio.h>
#include <string.h>

#include "dp_master/param_channel.h"

int rig_ctl_slave_index(const dp_master_t *m, uint8_t address)
{
    for (unsigned i = 0; i < m->num_slaves; i++) {
        if (m->slaves[i].cfg.address == address) {
            return (int)i;
        }
    }
    return -1;
}

bool rig_ctl_has_param_channel(const dp_master_slave_t *sl)
{
    dfp21b_pd_cfg_t pd;
    return dfp21b_check_cfg(sl->cfg.cfg, sl->cfg.cfg_len, &pd) && pd.param_channel;
}

/* ---- the cyclic MOVILINK channel ----------------------------------------------------------- */

static bool start_channel(rig_ctl_t *c, rig_cmd_t *cmd, unsigned idx)
{
    rig_t *r = c->rig;
    dp_master_slave_t *sl = &r->master.slaves[idx];
    if (!rig_ctl_has_param_channel(sl) || sl->out_len < ML_TELEGRAM_LEN) {
        rig_cmd_fail(cmd, 409, "the slave's configuration has no parameter channel (F3/B7)");
        return false;
    }
    uint8_t service = !cmd->write ? ML_SVC_READ : cmd->flag ? ML_SVC_WRITE_VOLATILE
                                                             : ML_SVC_WRITE;
    uint8_t out[DP_MASTER_MAX_IO];
    memcpy(out, sl->outputs, sl->out_len);
    dp_master_param_sync(&c->param, sl->inputs);
    dp_master_param_start(&c->param, service, cmd->index, (uint32_t)cmd->value, out);
    dp_master_set_outputs(&r->master, idx, out, sl->out_len);
    return true;
}

static bool advance_channel(rig_ctl_t *c, rig_cmd_t *cmd, const dp_master_slave_t *sl)
{
    if (!dp_master_param_done(&c->param, sl->inputs)) {
        return false;
    }
    cmd->status = 200;
    if ((sl->inputs[0] & ML_MGMT_ERROR) != 0u) {
        cmd->refused = true;
        ml_error_text(sl->inputs, cmd->error, sizeof cmd->error);
    } else {
        cmd->result = (int32_t)ml_data(sl->inputs);
    }
    return true;
}

/* ---- data set 47 (class 1 or class 2) ------------------------------------------------------ */

static bool start_ds47(rig_ctl_t *c, const rig_cmd_t *cmd, dp_master_acyc_port_t port)
{
    memset(&c->ds47, 0, sizeof c->ds47);
    c->ds47_ref = (uint8_t)(c->ds47_ref % 255u + 1u); /* 1..255: reference 0 is refused */
    c->ds47.ref = c->ds47_ref;
    c->ds47.id = DS47_ID_MOVILINK;
    c->ds47.n = 1;
    c->ds47.p[0].attribute = !cmd->write ? DS47_ATTR_ML_READ
                             : cmd->flag ? DS47_ATTR_ML_WRITE_VOLATILE
                                         : DS47_ATTR_ML_WRITE;
    c->ds47.p[0].number = cmd->index;
    c->ds47.p[0].value = (uint32_t)cmd->value;
    memset(&c->call, 0, sizeof c->call);
    if (dp_master_ds47_start(&c->call, port, &c->ds47, NULL, NULL, rig_now_us(c->rig)) != 0) {
        return false;
    }
    rig_wake(c->rig);
    return true;
}

/* The finished call's answer into cmd: a value, a MOVILINK refusal, or a failed service. */
static void ds47_result(const rig_ctl_t *c, rig_cmd_t *cmd)
{
    cmd->status = 200;
    if (!c->call.ok) {
        cmd->status = 502;
        (void)snprintf(cmd->error, sizeof cmd->error, "data set 47: %.180s",
                       c->call.error[0] != '\0' ? c->call.error : "negative DP-V1 response");
        return;
    }
    dp_master_ds47_rsp_t rsp;
    char err[160];
    if (!dp_master_ds47_parse(&c->ds47, c->call.data, c->call.len, &rsp, err, sizeof err)) {
        cmd->status = 502;
        (void)snprintf(cmd->error, sizeof cmd->error, "data set 47: %.180s", err);
        return;
    }
    if (!rsp.p[0].ok) {
        cmd->refused = true;
        dp_master_ml_error_value_text(rsp.p[0].error, cmd->error, sizeof cmd->error);
        return;
    }
    cmd->result = rsp.p[0].has_value ? (int32_t)rsp.p[0].value : cmd->value;
}

/* ---- a class-2 connection per service ------------------------------------------------------ */

static void c2_opened(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    (void)now;
    rig_ctl_t *c = ctx;
    c->c2_open_done = true;
    c->c2_open_ok = r->ok;
}

static void c2_aborted(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    (void)r;
    (void)now;
    rig_ctl_t *c = ctx;
    c->c2_abort_done = true;
}

/* The connection belongs to the master station and uses its address, so the slave sees one
 * initiator whose FCB sequence the master already keeps (dp_master.h). */
static bool start_c2(rig_ctl_t *c, rig_cmd_t *cmd)
{
    rig_t *r = c->rig;
    if (!r->master.running) {
        rig_cmd_fail(cmd, 409, "the master is stopped: class-2 telegrams go out only while it "
                               "runs (POST /api/v1/master/run)");
        return false;
    }
    dp_master_c2_cfg_t cc = {.slave = cmd->card, .address = r->master.cfg.address};
    if (!c->c2_attached) {
        dp_master_c2_init(&c->c2, &cc);
        if (dp_master_add_c2(&r->master, &c->c2) != 0) {
            rig_cmd_fail(cmd, 409, "the master has no room for another class-2 connection");
            return false;
        }
        c->c2_attached = true;
    }
    if (dp_master_c2_state(&c->c2) != DP_MASTER_C2_CLOSED || dp_master_c2_busy(&c->c2) ||
        c->c2.on_wire) {
        rig_cmd_fail(cmd, 409, "the last class-2 connection is still closing; try again");
        return false;
    }
    dp_master_c2_init(&c->c2, &cc); /* closed and off the wire: the master holds only the pointer */
    c->c2_open_done = false;
    c->c2_open_ok = false;
    c->c2_abort_done = false;
    if (dp_master_c2_open(&c->c2, c2_opened, c, rig_now_us(r)) != 0) {
        rig_cmd_fail(cmd, 409, "the class-2 connection cannot be opened now");
        return false;
    }
    c->c2_stage = RIG_C2_OPENING;
    rig_wake(r);
    return true;
}

/* Aborts the connection if it is open; true when nothing is left to wait for. */
static bool close_c2(rig_ctl_t *c)
{
    if (dp_master_c2_state(&c->c2) != DP_MASTER_C2_CLOSED &&
        dp_master_c2_abort(&c->c2, 0, c2_aborted, c, rig_now_us(c->rig)) == 0) {
        c->c2_stage = RIG_C2_CLOSING;
        rig_wake(c->rig);
        return false;
    }
    c->c2_stage = RIG_C2_IDLE;
    return true;
}

static bool advance_c2(rig_ctl_t *c, rig_cmd_t *cmd)
{
    switch (c->c2_stage) {
    case RIG_C2_OPENING:
        if (!c->c2_open_done) {
            return false;
        }
        if (!c->c2_open_ok) {
            cmd->status = 502;
            (void)snprintf(cmd->error, sizeof cmd->error,
                           "class-2 connection to slave %u not opened: %.150s", cmd->card,
                           dp_master_c2_error(&c->c2));
            c->c2_stage = RIG_C2_IDLE;
            return true;
        }
        if (!start_ds47(c, cmd, dp_master_c2_port(&c->c2))) {
            rig_cmd_fail(cmd, 409, "the class-2 connection did not take the request");
            return close_c2(c);
        }
        c->c2_stage = RIG_C2_CALLING;
        return false;
    case RIG_C2_CALLING:
        if (!dp_master_call_done(&c->call)) {
            return false;
        }
        ds47_result(c, cmd);
        return close_c2(c);
    case RIG_C2_CLOSING:
        if (!c->c2_abort_done && dp_master_c2_state(&c->c2) != DP_MASTER_C2_CLOSED) {
            return false;
        }
        c->c2_stage = RIG_C2_IDLE;
        return true;
    case RIG_C2_IDLE:
        break;
    }
    return true;
}

/* ---- one service at a time ----------------------------------------------------------------- */

bool rig_ctl_param_start(rig_ctl_t *c, rig_cmd_t *cmd)
{
    if (cmd->via == RIG_VIA_C2) {
        return start_c2(c, cmd); /* class 2 needs no start-up: any station address will do */
    }
    rig_t *r = c->rig;
    int idx = rig_ctl_slave_index(&r->master, cmd->card);
    if (idx < 0) {
        rig_cmd_fail(cmd, 404, "the master has no slave with that address");
        return false;
    }
    dp_master_slave_t *sl = &r->master.slaves[idx];
    if (sl->phase != DP_MASTER_PHASE_DATA_EXCH) {
        cmd->status = 409;
        (void)snprintf(cmd->error, sizeof cmd->error, "slave %u is not in data exchange (%s)",
                       sl->cfg.address, dp_master_phase_name(sl->phase));
        return false;
    }
    if (cmd->via == RIG_VIA_CHANNEL) {
        return start_channel(c, cmd, (unsigned)idx);
    }
    if (!dp_master_prm_is_dpv1(sl->cfg.prm, sl->cfg.prm_len)) {
        rig_cmd_fail(cmd, 409, "the slave is not parameterised for DP-V1 (data set 47 needs it)");
        return false;
    }
    if (!start_ds47(c, cmd, dp_master_c1_port(&r->master, (unsigned)idx))) {
        rig_cmd_fail(cmd, 409, "the class-1 channel is busy");
        return false;
    }
    return true;
}

bool rig_ctl_param_advance(rig_ctl_t *c, rig_cmd_t *cmd)
{
    if (cmd->via == RIG_VIA_C2) {
        return advance_c2(c, cmd);
    }
    rig_t *r = c->rig;
    int idx = rig_ctl_slave_index(&r->master, cmd->card);
    if (idx < 0) {
        rig_cmd_fail(cmd, 404, "the slave left the master's list");
        return true;
    }
    if (cmd->via == RIG_VIA_CHANNEL) {
        return advance_channel(c, cmd, &r->master.slaves[idx]);
    }
    if (!dp_master_call_done(&c->call)) {
        return false;
    }
    ds47_result(c, cmd);
    return true;
}

void rig_ctl_param_give_up(rig_ctl_t *c)
{
    if (c->c2_stage != RIG_C2_IDLE) {
        (void)close_c2(c);
        c->c2_stage = RIG_C2_IDLE; /* a later service waits until the connection is closed */
    }
}
