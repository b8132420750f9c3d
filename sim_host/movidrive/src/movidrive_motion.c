/* The emulated MOVIDRIVE's motion in simulated time: ramps towards the setpoint, position,
 * currents (README.md "Ramps", "Current model"). Integer arithmetic with carried remainders,
 * so any tick size gives the same trajectory. */
#include "movidrive_internal.h"

#define US_PER_MS 1000
#define TICK_WHILE_RAMPING_US 1000u /* deadline asked for while the speed still changes */
#define MAX_STEP_US 1000000u        /* integration step: keeps the products in int64 */

/* Ramp time in ms for a 3000 rpm change: `up` = |n| growing, `positive` = CW rotation. */
static int32_t ramp_ms(const movidrive_t *md, const movidrive_derived_t *d, bool up,
                       bool positive)
{
    bool set2 = movidrive_ramp_set_2_d(md, d);
    switch (md->mode) {
    case MODE_RAPID:
        return movidrive_ram_value(md, set2 ? IDX_P146_STOP_RAMP2 : IDX_P136_STOP_RAMP);
    case MODE_EMERGENCY:
        return movidrive_ram_value(md, set2 ? IDX_P147_EMERGENCY_RAMP2 : IDX_P137_EMERGENCY_RAMP);
    default:
        break;
    }
    uint16_t w;
    if (d->po_enabled && md->po_received && movidrive_po_word_d(md, d, PO_RAMP, &w)) {
        return w; /* PO "RAMP": ms, up and down alike (I: 1 digit = 1 ms as on MOVIMOT) */
    }
    if (positive) {
        if (up) {
            return movidrive_ram_value(md, set2 ? IDX_P140_RAMP2_UP : MOVIDRIVE_IDX_P130_RAMP_UP);
        }
        return movidrive_ram_value(md, set2 ? IDX_P141_RAMP2_DOWN : MOVIDRIVE_IDX_P131_RAMP_DOWN);
    }
    if (up) {
        return movidrive_ram_value(md, set2 ? IDX_P142_RAMP2_UP_CCW : IDX_P132_RAMP_UP_CCW);
    }
    return movidrive_ram_value(md, set2 ? IDX_P143_RAMP2_DOWN_CCW : IDX_P133_RAMP_DOWN_CCW);
}

/* Moves the actual speed towards the setpoint for dt_us of simulated time. A reversal is two
 * segments: down to 0 on the down ramp, then up on the other direction's up ramp. */
static void integrate_speed(movidrive_t *md, const movidrive_derived_t *d, uint32_t dt_us)
{
    /* budget in 0.001 rpm x ms: a ramp of t ms moves RAMP_REFERENCE_MRPM per t ms */
    int64_t budget = (int64_t)dt_us * (RAMP_REFERENCE_MRPM / US_PER_MS) + md->ramp_residue;
    md->ramp_residue = 0;
    int32_t target = md->speed_setpoint_mrpm;
    while (md->speed_actual_mrpm != target) {
        int32_t n = md->speed_actual_mrpm;
        bool up;
        int32_t seg_end;
        if (n == 0 || (n > 0 && target > n) || (n < 0 && target < n)) {
            up = true;
            seg_end = target;
        } else {
            up = false; /* towards zero: down to the target, or to 0 if it is across */
            seg_end = ((n > 0 && target > 0) || (n < 0 && target < 0)) ? target : 0;
        }
        bool positive = n > 0 || (n == 0 && target > 0);
        int64_t t = ramp_ms(md, d, up, positive);
        if (t <= 0) {
            md->speed_actual_mrpm = seg_end;
            continue;
        }
        int64_t dist = (int64_t)seg_end - n;
        int64_t adist = dist < 0 ? -dist : dist;
        if (budget >= adist * t) {
            budget -= adist * t;
            md->speed_actual_mrpm = seg_end;
            continue;
        }
        int64_t step = budget / t;
        md->ramp_residue = budget % t;
        md->speed_actual_mrpm = (int32_t)(n + (dist < 0 ? -step : step));
        return;
    }
}

/* P003 over one integration step from speed n0 to the current speed: trapezoid, INC_PER_REV
 * increments per revolution, remainder carried. */
static void advance_position(movidrive_t *md, int32_t n0, uint32_t dt_us)
{
    int64_t num = ((int64_t)n0 + md->speed_actual_mrpm) * dt_us * (INC_PER_REV / 2) +
                  md->pos_residue;
    const int64_t den = 60LL * 1000000 * 1000; /* s/min x us/s x 0.001 rpm */
    md->position_inc += (int32_t)(num / den);
    md->pos_residue = num % den;
}

static int32_t abs32(int32_t v)
{
    return v < 0 ? -v : v;
}

void movidrive_update_currents(movidrive_t *md, const movidrive_derived_t *d)
{
    if (!md->output_stage_enabled) {
        md->current_mpct = 0;
        md->active_current_mpct = 0;
        return;
    }
    int32_t n = md->speed_actual_mrpm;
    int32_t load = (int32_t)((int64_t)abs32(n) * LOAD_MPCT_AT_1500 / 1500000);
    int32_t accel = md->accel != 0 ? ACCEL_MPCT : 0;
    int32_t active = load + (md->accel > 0 ? accel : -accel);
    int32_t out = MAGNETISING_MPCT + load + accel;
    int32_t limit = d->key[DK_P303];
    if (limit > 0 && out > limit) {
        out = limit;
    }
    md->current_mpct = out;
    md->active_current_mpct = n < 0 ? -active : active;
}

/* While ramping: 1 ms on. Otherwise as far ahead as the wrapping clock can say ("no
 * deadline" taken as a distance from now). */
static hal_time_us_t next_deadline(const movidrive_t *md, hal_time_us_t now)
{
    return now + (md->speed_actual_mrpm != md->speed_setpoint_mrpm ? TICK_WHILE_RAMPING_US
                                                                   : HAL_TIME_NO_DEADLINE_US);
}

hal_time_us_t movidrive_tick(movidrive_t *md, hal_time_us_t now)
{
    if (!md->ticked) {
        md->ticked = true;
        md->last_tick = now;
        movidrive_evaluate(md);
        return now + TICK_WHILE_RAMPING_US;
    }
    int32_t dt = hal_time_diff(now, md->last_tick);
    if (dt <= 0) {
        return next_deadline(md, now);
    }
    md->last_tick = now;
    movidrive_evaluate(md);
    const movidrive_derived_t *d = movidrive_derive(md);
    int32_t before = md->speed_actual_mrpm;
    uint32_t left = (uint32_t)dt;
    while (left > 0) {
        uint32_t chunk = left > MAX_STEP_US ? MAX_STEP_US : left;
        int32_t n0 = md->speed_actual_mrpm;
        integrate_speed(md, d, chunk);
        advance_position(md, n0, chunk);
        left -= chunk;
    }
    int32_t after = md->speed_actual_mrpm;
    md->accel = (int8_t)(abs32(after) > abs32(before) ? 1 : abs32(after) < abs32(before) ? -1 : 0);
    movidrive_evaluate(md); /* a stop ramp that reached 0 switches the output stage off */
    return next_deadline(md, now);
}
