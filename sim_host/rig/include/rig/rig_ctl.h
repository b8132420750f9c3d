/* The bridge between a running rig and clients in other threads (the HTTP control API).
 *
 * The bus loop owns the rig; nothing outside it touches the rig's structs. Instead:
 * - the loop publishes a snapshot (plain values) into one of RIG_CTL_SNAPS buffers; a client
 *   pins the current one with an atomic count and copies it; the loop fills a buffer nobody
 *   has pinned, or skips that publication when there is none;
 * - log events go into a ring of RIG_CTL_EVENTS entries that clients read by sequence number,
 *   each entry checked by its own stamp (a seqlock), so readers take no lock; a client that
 *   falls behind loses the oldest and is told how many;
 * - actions are queued as commands in slots whose state is one atomic; the loop carries them
 *   out between two bus events (rig_ctl_service) and a client waits for the result with a
 *   timeout. A command whose client gave up before the loop took it up is withdrawn and never
 *   carried out (the client is told so); one the loop had already started is carried out to
 *   its end and then freed. Either way the rig sees exactly what the clients were told, and no
 *   slot stays taken.
 * The loop never waits on anything a client holds: writers of log events from other threads
 * share a mutex the loop only ever tries (its events wait in a private queue meanwhile), and
 * clients sleep on a futex word the loop only increments and wakes. A slow, stuck or starved
 * client can therefore never delay the bus. */
#ifndef RIG_RIG_CTL_H
#define RIG_RIG_CTL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_master/param_channel.h"
#include "rig/rig.h"
#include "rig/rig_doc.h"

#define RIG_CTL_EVENTS 4096u
#define RIG_CTL_CMDS 16u
#define RIG_CTL_TEXT 240u
#define RIG_CTL_SNAPS 4u    /* the current snapshot, the one being filled, two being read */
#define RIG_CTL_STAGED 256u /* the loop's events waiting while another thread writes one */
#define RIG_CTL_SNAP_WRITER 0x80000000u /* in snap_use: the loop is filling that buffer */
/* The refusal of a card command (409) when more than one card of the line answers to its
 * address (DIP switches changed, then a power cycle): either card might be the one meant.
 * Arguments: the number of cards, the address. The HTTP routes answer reads with it too. */
#define RIG_CTL_AMBIGUOUS_FMT "%u cards answer to address %u (DIP switches); the API cannot " \
                              "tell which one is meant"

typedef enum rig_log_level {
    RIG_LOG_ERROR = 0,
    RIG_LOG_WARN,
    RIG_LOG_INFO,
    RIG_LOG_DEBUG,
} rig_log_level_t;

typedef struct rig_ctl_event {
    uint64_t seq;
    uint64_t t_us;
    rig_log_level_t level;
    char source[16]; /* "card 4", "drive 4", "master", "sim" */
    char kind[12];   /* docs/api.md */
    char text[RIG_CTL_TEXT];
} rig_ctl_event_t;

/* ---- snapshot ------------------------------------------------------------------------------ */

typedef struct rig_snap_card {
    uint8_t address;
    uint8_t next_address;
    bool cable;
    bool on_bus;
    uint8_t dp_state;    /* dp_state_t */
    uint8_t baud_state;  /* dp_baud_state_t */
    uint32_t baud;
    int16_t master;      /* -1: none */
    uint32_t watchdog_ms;
    uint8_t cfg[32];
    uint8_t cfg_len;
    uint8_t diag[32];
    uint8_t diag_len;
    uint8_t led[HAL_LED_COUNT]; /* hal_led_mode_t */
    char p090[16];
    uint16_t po[DFP21B_MAX_PD];
    uint16_t pi[DFP21B_MAX_PD];
    uint8_t pd_words;
    uint32_t p819_ms;
    bool dpv1_enabled;
    bool msac1_open;
    bool msac2_open[2];
    int16_t msac2_master[2];
    char nvm_note[1024]; /* both files' notes of card_station_init, each a few hundred characters */
    char eeprom_path[160];
    char card_nvm_path[160];
    /* the drive */
    bool has_drive;
    uint16_t control_word;
    uint16_t status_word;
    bool enabled;
    uint8_t fault;
    int32_t setpoint_mrpm;
    int32_t speed_mrpm;
    int32_t current_mpct;
    int32_t ramp_up_ms;
    int32_t ramp_down_ms;
    bool di00;
} rig_snap_card_t;

typedef struct rig_snap_slave {
    uint8_t address;
    uint8_t phase; /* dp_master_phase_t */
    uint32_t cycles;
    uint8_t outputs[64];
    uint16_t out_len;
    uint8_t inputs[64];
    uint16_t in_len;
    bool param_channel;
    uint8_t diag[32];
    uint8_t diag_len;
} rig_snap_slave_t;

typedef struct rig_snapshot {
    uint64_t t_us;
    uint8_t medium; /* rig_medium_t */
    char medium_name[96];
    uint32_t medium_baud;
    uint8_t num_cards;
    rig_snap_card_t cards[RIG_MAX_CARDS];
    bool has_master;
    uint8_t master_address;
    bool master_running;
    uint32_t master_baud;
    uint8_t num_slaves;
    rig_snap_slave_t slaves[DP_MASTER_MAX_SLAVES];
} rig_snapshot_t;

/* ---- commands ------------------------------------------------------------------------------ */

typedef enum rig_cmd_type {
    RIG_CMD_INPUTS = 0,  /* card: flag = DI00 */
    RIG_CMD_FAULT,       /* card: value = fault number */
    RIG_CMD_CABLE,       /* card: flag = connected */
    RIG_CMD_POWER_CYCLE, /* card */
    RIG_CMD_DIP,         /* card: value = address */
    RIG_CMD_PARAM_READ,  /* card: index (directly at the drive) */
    RIG_CMD_PARAM_WRITE, /* card: index, value, flag = volatile */
    RIG_CMD_MASTER_RUN,  /* flag = running */
    RIG_CMD_MASTER_OUTPUTS, /* card = slave address; words/num_words (from word first_word) or
                               raw/raw_len */
    RIG_CMD_MASTER_PARAM, /* card = slave address; via, index, value, flag = volatile, write */
} rig_cmd_type_t;

typedef enum rig_param_via {
    RIG_VIA_CHANNEL = 0, /* the cyclic 8-octet MOVILINK channel */
    RIG_VIA_DS47,        /* DP-V1 class 1, data set 47 with a MOVILINK request */
    RIG_VIA_C2,          /* a DP-V1 class-2 connection opened for the request, then aborted */
} rig_param_via_t;

/* Where a class-2 service stands (RIG_VIA_C2). */
typedef enum rig_c2_stage {
    RIG_C2_IDLE = 0,
    RIG_C2_OPENING, /* Initiate sent; waiting for the connection */
    RIG_C2_CALLING, /* data set 47 Write/Read on the open connection */
    RIG_C2_CLOSING, /* Abort sent; the answer stays in the command until it is taken */
} rig_c2_stage_t;

typedef struct rig_cmd {
    rig_cmd_type_t type;
    uint8_t card;     /* the card's (or master's slave's) bus address */
    bool flag;
    bool write;
    int32_t value;
    uint16_t index;
    rig_param_via_t via;
    uint16_t words[DFP21B_MAX_PD];
    uint8_t num_words;
    uint8_t raw[64];
    uint8_t raw_len;
    bool raw_given;
    /* result */
    int status;        /* HTTP status: 200, 400, 404, 409, 504 */
    bool refused;      /* the drive answered with an error (a service that worked) */
    int32_t result;    /* the value read or written */
    char error[200];
} rig_cmd_t;

typedef enum rig_slot_state {
    RIG_SLOT_FREE = 0,
    RIG_SLOT_FILLING,  /* a client is writing its command into the slot */
    RIG_SLOT_QUEUED,
    RIG_SLOT_RUNNING,  /* a master parameter service over the bus */
    RIG_SLOT_DONE,
    RIG_SLOT_ABANDONED, /* the client gave up while it ran; freed when done */
} rig_slot_state_t;

/* One log event of the ring, copied word by word through relaxed atomics: a reader may copy
 * while a writer overwrites it, and the stamp tells it so (a seqlock without data races). */
#define RIG_CTL_EVENT_WORDS ((sizeof(rig_ctl_event_t) + 7u) / 8u)
typedef struct rig_ctl_ev_slot {
    _Atomic uint64_t stamp; /* 2 seq + 1 while written, 2 seq + 2 once complete; 0: never */
    _Atomic uint64_t words[RIG_CTL_EVENT_WORDS];
} rig_ctl_ev_slot_t;

typedef struct rig_ctl {
    rig_t *rig;
    bool read_only;
    const char *mode;         /* "demo", "slave", "master", "replay" */
    atomic_bool closing;
    /* Clients sleep on gen (a futex word) while waiting for an event, a command's end or the
     * close; whoever changes one of those increments gen and wakes them when waiters > 0. */
    atomic_uint gen;
    atomic_uint waiters;
    /* The snapshot: snaps[snap_current] is the newest complete one. snap_use[i] counts the
     * clients copying snaps[i], plus RIG_CTL_SNAP_WRITER while the loop fills it. */
    rig_snapshot_t snaps[RIG_CTL_SNAPS];
    atomic_uint snap_use[RIG_CTL_SNAPS];
    atomic_uint snap_current;
    uint64_t snaps_skipped;   /* loop side: publications skipped, every buffer being read */
    _Atomic uint64_t now_us;  /* the rig's clock at the loop's last turn (rig_ctl_time_us) */
    /* Log events: ring[seq % N]; next_seq is the seq of the next event, stored once the event
     * is complete. Writers take ev_lock (the loop only tries it). */
    rig_ctl_ev_slot_t ring[RIG_CTL_EVENTS];
    _Atomic uint64_t next_seq;
    pthread_mutex_t ev_lock;
    pthread_t loop_thread;    /* the thread that called rig_ctl_init */
    rig_ctl_event_t staged[RIG_CTL_STAGED]; /* loop side: its events not yet in the ring */
    unsigned staged_n;
    uint64_t staged_dropped;
    /* Commands: a slot's state is slot[k] (rig_slot_state_t); cmds[k] belongs to the client
     * while FREE or FILLING and once DONE, to the loop while QUEUED (taken), RUNNING or
     * ABANDONED. Each handover is a release store or compare-exchange of slot[k]. */
    rig_cmd_t cmds[RIG_CTL_CMDS];
    atomic_int slot[RIG_CTL_CMDS];
    uint64_t slot_deadline_us[RIG_CTL_CMDS]; /* a running service's time limit (rig time) */
    int wake_fd;              /* eventfd the loop waits on; -1 on the in-memory bus */
    /* the master's parameter service in progress (one at a time, like a PLC's FB) */
    int active_slot;          /* -1: none */
    dp_master_param_t param;
    dp_master_call_t call;
    dp_master_ds47_req_t ds47;
    uint8_t ds47_ref;         /* request reference of the last data set 47 request */
    /* The class-2 connection of the master station (its own address), attached to the master
     * at the first class-2 service and opened for each one. */
    dp_master_c2_t c2;
    bool c2_attached;
    rig_c2_stage_t c2_stage;
    bool c2_open_done;
    bool c2_open_ok;
    bool c2_abort_done;
    /* loop side */
    uint64_t last_publish_ns;
    /* The bus monitor's JSON (GET /api/v1/bus), published by whoever runs a monitor on this
     * rig; NULL: this process has none. Set before the HTTP server starts, never changed. */
    rig_doc_t *bus;
} rig_ctl_t;

int rig_ctl_init(rig_ctl_t *c, rig_t *r, const char *mode, bool read_only);
void rig_ctl_destroy(rig_ctl_t *c);

/* Publishes a log event. Any thread may call it. In the loop's thread (the one that called
 * rig_ctl_init) it never waits: when another thread is writing an event, the loop's waits in a
 * private queue until the next call or rig_ctl_service (kept in order; should the queue fill
 * up, one "lost" event says how many it dropped). */
void rig_ctl_event(rig_ctl_t *c, uint64_t t_us, rig_log_level_t level, const char *source,
                   const char *kind, const char *text);
/* Runs queued commands, advances a master parameter service, publishes the snapshot when it is
 * older than publish_ns (wall clock). Call often from the loop. */
void rig_ctl_service(rig_ctl_t *c, uint64_t publish_every_ns);
/* Registers the wake-up descriptor with the rig's wall-clock loop. */
int rig_ctl_attach(rig_ctl_t *c);
/* Wakes every client waiting in rig_ctl_wait or rig_ctl_submit, so it looks again at what it
 * waits for (e.g. a server that is stopping). Never blocks. */
void rig_ctl_kick(rig_ctl_t *c);

/* Client side. Copies the newest snapshot (never waits for the loop). */
void rig_ctl_snapshot(rig_ctl_t *c, rig_snapshot_t *out);
/* Queues cmd and waits up to timeout_ms for the loop to carry it out; cmd gets the result.
 * Returns false on timeout (cmd->status = 504; the text says whether the command was withdrawn
 * unrun or may still be carried out) or a full queue (503). */
bool rig_ctl_submit(rig_ctl_t *c, rig_cmd_t *cmd, unsigned timeout_ms);
/* Copies events with seq >= since into out (at most max, oldest first). Returns how many;
 * *lost = how many with seq >= since are no longer held. */
size_t rig_ctl_events(rig_ctl_t *c, uint64_t since, rig_ctl_event_t *out, size_t max,
                      uint64_t *lost);
/* Waits until an event with seq >= since exists or timeout_ms passes. */
void rig_ctl_wait(rig_ctl_t *c, uint64_t since, unsigned timeout_ms);
uint64_t rig_ctl_next_seq(rig_ctl_t *c);
/* The rig's clock (t_us of the events) as of the loop's last turn, for events that other
 * threads log (the API's audit), without copying a snapshot. */
uint64_t rig_ctl_time_us(rig_ctl_t *c);

#endif
