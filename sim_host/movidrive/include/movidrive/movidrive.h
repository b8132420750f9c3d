/* An emulated MOVIDRIVE MDX61B: the inverter behind the DFP21B card.
 *
 * It speaks what the real unit speaks to an option card or on SBus: 8-byte MOVILINK parameter
 * telegrams (movidrive_param) and process-data words (movidrive_process_outputs/_inputs). The
 * parameter table is generated from sim_host/movidrive/data/parameters.csv; non-volatile values live in an
 * EEPROM image file that survives restarts, written so that a crash leaves the old or the new
 * value. Time is passed in (movidrive_tick) so ramps and timeouts run in simulated time too.
 *
 * The struct is caller-owned; nothing is allocated. */
#ifndef MOVIDRIVE_MOVIDRIVE_H
#define MOVIDRIVE_MOVIDRIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_nvm.h"
#include "hal/hal_time.h"
#include "movilink/movilink_link.h"
#include "movilink/movilink_wire.h"

/* Some indices the card, the demo and the tests use by name. */
#define MOVIDRIVE_IDX_FIRMWARE 8300u      /* P076, reads 0x311C7289 */
#define MOVIDRIVE_IDX_SPEED 8318u         /* P000, 0.001 rpm */
#define MOVIDRIVE_IDX_STATUS 8310u        /* P010..P013, low word = status word 1 */
#define MOVIDRIVE_IDX_P090 8451u
#define MOVIDRIVE_IDX_P100_SETPOINT_SOURCE 8461u
#define MOVIDRIVE_IDX_P101_CONTROL_SOURCE 8462u
#define MOVIDRIVE_IDX_P130_RAMP_UP 8470u
#define MOVIDRIVE_IDX_P131_RAMP_DOWN 8471u
#define MOVIDRIVE_IDX_P160_N11 8489u
#define MOVIDRIVE_IDX_P302_MAX_SPEED 8517u
#define MOVIDRIVE_IDX_P803_PARAM_LOCK 8595u
#define MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT 8606u
#define MOVIDRIVE_IDX_P831_FIELDBUS_REACTION 8610u
#define MOVIDRIVE_IDX_P870_PO1 8304u
#define MOVIDRIVE_IDX_P876_PO_ENABLE 8622u
#define MOVIDRIVE_IDX_IPOS_H0 11000u
#define MOVIDRIVE_IPOS_VARS 512u
#define MOVIDRIVE_SOURCE_FIELDBUS_SETPOINT 3u /* P100 = FIELDBUS */
#define MOVIDRIVE_SOURCE_FIELDBUS_CONTROL 2u  /* P101 = FIELDBUS */

/* Status word 1, low byte (protocol.md §C3.3). */
#define MOVIDRIVE_SW_OUTPUT_STAGE_ENABLED 0x0001u
#define MOVIDRIVE_SW_READY 0x0002u
#define MOVIDRIVE_SW_PO_DATA_ENABLED 0x0004u
#define MOVIDRIVE_SW_RAMP_SET_2 0x0008u
#define MOVIDRIVE_SW_PARAM_SET_2 0x0010u
#define MOVIDRIVE_SW_FAULT 0x0020u

/* Control word 1, basic block (protocol.md §C3.1). */
#define MOVIDRIVE_CW_CONTROLLER_INHIBIT 0x0001u
#define MOVIDRIVE_CW_ENABLE_RAPID_STOP 0x0002u /* 1 = enable, 0 = rapid stop */
#define MOVIDRIVE_CW_ENABLE_STOP 0x0004u       /* 1 = enable, 0 = stop */
#define MOVIDRIVE_CW_HOLD 0x0008u
#define MOVIDRIVE_CW_RAMP_SET_2 0x0010u
#define MOVIDRIVE_CW_PARAM_SET_2 0x0020u
#define MOVIDRIVE_CW_RESET 0x0040u /* fault reset on the rising edge */

/* Fault numbers the emulation raises. F28 for the fieldbus timeout is an assumption
 * (protocol.md §C3.3 lists it as inferred). */
#define MOVIDRIVE_FAULT_FIELDBUS_TIMEOUT 28u

#define MOVIDRIVE_MAX_PARAMS 512u
/* Widest index range (first to last table entry) the per-drive index-to-position table covers;
 * the generated table spans 8300..8891. */
#define MOVIDRIVE_SLOT_SPAN 1024u

typedef struct movidrive_param_def {
    uint16_t index;
    int32_t min;
    int32_t max;
    int32_t def;
    uint8_t quantity;   /* PNO quantity index (read scale), 0xFF none */
    int8_t conversion;  /* PNO conversion index */
    uint8_t flags;      /* MOVIDRIVE_PF_* */
    uint32_t enum_mask; /* added: bit n set = value n defined (enumeration); 0 = no enumeration */
} movidrive_param_def_t;

#define MOVIDRIVE_PF_READ_ONLY 0x01u
#define MOVIDRIVE_PF_NON_VOLATILE 0x02u   /* kept in EEPROM ("N") */
#define MOVIDRIVE_PF_INHIBIT_REQUIRED 0x04u /* "R": write only with controller inhibit */
#define MOVIDRIVE_PF_LOCK_EXEMPT 0x08u    /* "S": writable even with parameter lock P803 */
#define MOVIDRIVE_PF_NO_VOLATILE 0x10u    /* write volatile not permitted */
#define MOVIDRIVE_PF_HAS_MIN 0x20u
#define MOVIDRIVE_PF_HAS_MAX 0x40u
/* added: min/max/value compared as uint32 (P092, P221, P222) */
#define MOVIDRIVE_PF_UNSIGNED 0x80u

/* Unit status (status word 1 high byte when bit 5 is clear; README.md lists the sources). */
#define MOVIDRIVE_UNIT_CONTROLLER_INHIBIT 1u
#define MOVIDRIVE_UNIT_NO_ENABLE 2u
#define MOVIDRIVE_UNIT_ENABLED 4u
#define MOVIDRIVE_UNIT_WAITING_FOR_DATA 16u

/* Read attribute, bytes 6..7 (MOVITRAC B coding, protocol.md §C1.3; assumed for MOVIDRIVE). */
#define MOVIDRIVE_ATTR_WRITE_ALLOWED 0x0001u
#define MOVIDRIVE_ATTR_EEPROM 0x0002u
#define MOVIDRIVE_ATTR_FACTORY_RAM 0x0004u
#define MOVIDRIVE_ATTR_FACTORY_EEPROM 0x0008u
#define MOVIDRIVE_ATTR_EEPROM_VALID_AT_INIT 0x0010u
#define MOVIDRIVE_ATTR_NO_INHIBIT_REQUIRED 0x0020u

/* EEPROM image (inside the hal_nvm byte array): header "MDEE", version, record count, IPOS
 * count; records (index u16, value i32, big-endian) for every N parameter in table order;
 * then H0..H511. movidrive_eeprom_size() gives the bytes the NVM must offer. */
#define MOVIDRIVE_EE_MAGIC 0x4D444545u
#define MOVIDRIVE_EE_VERSION 1u
#define MOVIDRIVE_EE_HEADER 12u
#define MOVIDRIVE_EE_RECORD 6u

/* The parameters the drive model consults on every poll: P100, P101, P876, P870..P872,
 * P873..P875, P302, P303. */
#define MOVIDRIVE_DERIVED_KEYS 11u
/* PO function codes (P870..P872 values) below this have their first PO slot noted. */
#define MOVIDRIVE_DERIVED_PO_FUNCTIONS 16u

/* What the drive model derives from those parameters, with their positions and the values it
 * was derived from. Kept while the table and those values stay the same, so that the model
 * does not look the same parameters up dozens of times per card poll; a value changed by any
 * means (a service, the EEPROM, a test writing ram[]) makes it stale, never wrong. */
typedef struct movidrive_derived {
    const movidrive_param_def_t *defs; /* the table it was derived for */
    size_t num_defs;
    bool complete;                       /* the table has all of them (else never current) */
    int16_t pos[MOVIDRIVE_DERIVED_KEYS]; /* positions in ram[], -1: not in the table (0) */
    int32_t key[MOVIDRIVE_DERIVED_KEYS]; /* the values derived from */
    bool setpoint_from_bus;              /* P100 = FIELDBUS */
    bool control_from_bus;               /* P101 = FIELDBUS */
    bool po_enabled;                     /* status bit 2 */
    uint8_t po_first[MOVIDRIVE_DERIVED_PO_FUNCTIONS]; /* function -> first PO1..PO3 slot, 3 none */
} movidrive_derived_t;

typedef struct movidrive_cfg {
    hal_nvm_t eeprom;        /* ops == NULL: no persistence (values reset at every start) */
    uint8_t sbus_address;    /* P813 */
    bool terminal_enable;    /* DI00 /CONTROLLER INHIBIT wired to +24 V (true = enabled) */
} movidrive_cfg_t;

typedef struct movidrive {
    movidrive_cfg_t cfg;
    const movidrive_param_def_t *defs; /* the generated table */
    size_t num_defs;
    int32_t ram[MOVIDRIVE_MAX_PARAMS];   /* current values, parallel to defs */
    int32_t ipos[MOVIDRIVE_IPOS_VARS];   /* H0..H511 */
    /* drive state */
    uint16_t po[ML_MAX_PD];
    uint16_t control_word;
    int32_t speed_setpoint_mrpm;  /* 0.001 rpm */
    int32_t speed_actual_mrpm;
    uint8_t fault;                /* 0 = none */
    bool warning;
    bool fieldbus_timeout;
    bool output_stage_enabled;
    ml_fieldbus_status_t fieldbus;
    hal_time_us_t last_tick;
    bool ticked;
    uint32_t eeprom_writes;
    /* added: */
    int32_t ee[MOVIDRIVE_MAX_PARAMS];      /* the EEPROM's values, parallel to defs (write volatile
                                       changes ram only) */
    int32_t ee_ipos[MOVIDRIVE_IPOS_VARS];
    bool ee_layout_ok;              /* the image in the NVM has this table's record layout;
                                       otherwise the next save writes the whole image */
    bool ee_usable;                 /* an NVM of sufficient size is configured */
    uint8_t po_count;               /* words in po[] */
    bool po_received;               /* any PO since init ("waiting for data" until then) */
    uint16_t ipos_po[ML_MAX_PD];    /* IPOS data area: every received PO word (PO4..PO10 only
                                       here; PO1..PO3 too, whatever P870..P872 say) */
    uint16_t ipos_pi[ML_MAX_PD];    /* what an IPOS program sends: PI words with P873..P875 =
                                       IPOS PI-DATA, and PI4..PI10 */
    uint8_t mode;                   /* internal drive mode (inhibit, stop kinds, run) */
    uint8_t fault_reaction;         /* P83x value that latched `fault` */
    uint8_t warning_code;           /* fault number shown with a warning (F28) */
    uint8_t warning_reaction;       /* P83x value of the active warning */
    int8_t accel;                   /* +1 speeding up, -1 slowing down, 0 steady (last tick) */
    int64_t ramp_residue;           /* ramp integration remainder (0.001 rpm x ms units) */
    int64_t pos_residue;
    int32_t position_inc;           /* P003, 4096 increments per motor revolution */
    int32_t current_mpct;           /* output current, 0.001 % I_N */
    int32_t active_current_mpct;
    bool have_fieldbus;             /* movidrive_fieldbus_status() was called */
    /* Index -> position in defs (-1: none) for the table movidrive_init set: the drive model
     * reads dozens of parameters per card poll, and a binary search for each was half of a
     * replay's time. Used only while defs and num_defs are still that table. */
    const movidrive_param_def_t *slot_defs;
    size_t slot_num;
    uint16_t slot_base;
    int16_t slot[MOVIDRIVE_SLOT_SPAN];
    movidrive_derived_t derived; /* brought up to date by every evaluation */
} movidrive_t;

/* Loads defaults, then the EEPROM image if there is a valid one. Returns 0, or -1 with a reason
 * (unreadable or corrupt image: the reason says which, and factory defaults are used). */
int movidrive_init(movidrive_t *md, const movidrive_cfg_t *cfg, char *err, size_t errlen);
/* One MOVILINK service, answered at once: rsp = the 8-octet response (error bit + class 8 code,
 * or the value). The handshake bit of req is ignored (SBus asynchronous mode). */
void movidrive_param(movidrive_t *md, const uint8_t req[ML_TELEGRAM_LEN],
                     uint8_t rsp[ML_TELEGRAM_LEN]);
/* Process data from the fieldbus (only acted on when P100/P101 = FIELDBUS and P876 = YES). */
void movidrive_process_outputs(movidrive_t *md, const uint16_t *po, uint8_t n);
void movidrive_process_inputs(const movidrive_t *md, uint16_t *pi, uint8_t n);
/* Fieldbus monitor values, P819 and the timeout flag from the card. */
void movidrive_fieldbus_status(movidrive_t *md, const ml_fieldbus_status_t *st);
/* Ramps, timeout reactions. Returns the next instant it wants to be called. */
hal_time_us_t movidrive_tick(movidrive_t *md, hal_time_us_t now);
/* P802 factory setting: defaults into RAM and EEPROM. */
int movidrive_factory_reset(movidrive_t *md);

/* Added. Status word 1 as PI "STATUS WORD1" and the low word of index 8310 show it. */
uint16_t movidrive_status_word(const movidrive_t *md);
/* DI00 /CONTROLLER INHIBIT changed (true = +24 V, enabled). */
void movidrive_set_terminal_enable(movidrive_t *md, bool enabled);
/* A fault the unit detected itself (a simulated over-temperature, ...): immediate switch-off,
 * recorded in P080..P084, reset like any fault (control word bit 6 edge). 0 does nothing. */
void movidrive_inject_fault(movidrive_t *md, uint8_t number);
/* Bytes the EEPROM (hal_nvm) must offer for the image. */
size_t movidrive_eeprom_size(void);
/* The table entry of an index, NULL if none (H0..H511 share one entry). */
const movidrive_param_def_t *movidrive_param_def(const movidrive_t *md, uint16_t index);
/* A parameter's current value as "Read" returns it; false for an unknown index. */
bool movidrive_read_value(const movidrive_t *md, uint16_t index, int32_t *value);

/* An in-process ml_link for the card: requests are answered through the given completion
 * function (normally dfp21b's) after `delay_us` of simulated time, to show that the card never
 * waits for its inverter. */
typedef struct movidrive_inproc_link {
    movidrive_t *md;
    void (*param_response)(void *card, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN]);
    void (*process_inputs)(void *card, const uint16_t *pi, uint8_t n);
    void *card;
    uint32_t delay_us;
    struct {
        bool pending;
        uint8_t rsp[ML_TELEGRAM_LEN];
        hal_time_us_t due;
    } ch[ML_MAX_CHANNELS];
    hal_time_us_t now;
    uint8_t pd_words;
    /* process_outputs leaves the PI push to the next movidrive_inproc_link_poll(), for a
     * caller that polls the link right after the card's poll, before any reply can go out. */
    bool pi_on_poll_only;
    /* What the card was last given: unchanged PI words are not pushed again, so the card does
     * not rebuild an input image that would come out the same. */
    bool pushed_valid;
    uint8_t pushed_words;
    uint16_t pushed[ML_MAX_PD];
} movidrive_inproc_link_t;

ml_link_t movidrive_inproc_link(movidrive_inproc_link_t *l);
/* Delivers due responses and PI words that changed since the last push. Returns the next
 * deadline. */
hal_time_us_t movidrive_inproc_link_poll(movidrive_inproc_link_t *l, hal_time_us_t now);
/* The same without the PI push: the drive's time runs to now and due responses arrive. For a
 * caller whose next step (the card taking outputs) pushes PI anyway and polls again after. */
hal_time_us_t movidrive_inproc_link_advance(movidrive_inproc_link_t *l, hal_time_us_t now);
/* The card restarted and forgot the PI it was given: the next push hands over every word. */
void movidrive_inproc_link_card_restarted(movidrive_inproc_link_t *l);

#endif
