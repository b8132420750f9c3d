/* A PROFIBUS-DP device database (GSD) file reader: the keywords of the GSD specification (PI
 * order no. 2.122) a master, a monitor and a conformance test need, and a consistency check of
 * what the file says against itself. README.md describes the syntax accepted and the checks.
 *
 * No globals, no heap: a gsd_t holds everything in arrays of the sizes below; a file that needs
 * more is refused with an error naming the line and the limit. gsd_t is large (about 250 KiB):
 * give it static storage or allocate it. */
#ifndef GSD_GSD_H
#define GSD_GSD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define GSD_MAX_MODULES 256u      /* Module ... EndModule blocks */
#define GSD_MAX_CFG_OCTETS 4096u  /* the config octets of all modules together */
#define GSD_MAX_USER_PRM 237u     /* Set_Prm's 244 DU octets less its 7 standard ones */
#define GSD_MAX_MODULE_PRM 8192u  /* the parameter octets of all modules together */
#define GSD_MAX_CONSTS 1024u      /* Ext_User_Prm_Data_Const lines, global and in modules */
#define GSD_MAX_REFS 1024u        /* Ext_User_Prm_Data_Ref lines, global and in modules */
#define GSD_MAX_PRM_DEFS 512u     /* ExtUserPrmData ... EndExtUserPrmData blocks */
#define GSD_MAX_VALUES 4096u      /* the listed values (1,2,4) of all ExtUserPrmData together */
#define GSD_MAX_TEXT_TABLES 256u  /* PrmText ... EndPrmText blocks */
#define GSD_MAX_TEXTS 4096u       /* Text(n) lines of all PrmText blocks together */
#define GSD_MAX_STRING 255u       /* characters of one quoted string that is kept */
#define GSD_MAX_CHARS 65536u      /* all kept strings together, each with its NUL */
#define GSD_MAX_LINE 4096u        /* characters of one line, continuation lines joined */
#define GSD_MAX_NOTES 64u         /* ignored keywords and repeated ones remembered */
#define GSD_ERR_LEN 256u          /* an error text fits in this (file name aside) */

/* The ten PROFIBUS rates in the order of their keywords (9.6_supp .. 12M_supp). */
#define GSD_RATE_COUNT 10u

/* The keywords kept as one number each (gsd_t.key, gsd_key()). */
typedef enum gsd_key {
    GSD_K_GSD_REVISION = 0,
    GSD_K_IDENT_NUMBER,
    GSD_K_PROTOCOL_IDENT,
    GSD_K_STATION_TYPE,
    GSD_K_FMS_SUPP,
    GSD_K_REVISION_NUMBER,
    GSD_K_REPEATER_CTRL_SIG,
    GSD_K_24V_PINS,
    GSD_K_AUTO_BAUD_SUPP,
    GSD_K_SET_SLAVE_ADD_SUPP,
    GSD_K_FREEZE_MODE_SUPP,
    GSD_K_SYNC_MODE_SUPP,
    GSD_K_FAIL_SAFE,
    GSD_K_MIN_SLAVE_INTERVALL,
    GSD_K_SLAVE_FAMILY,
    GSD_K_MODULAR_STATION,
    GSD_K_MAX_MODULE,
    GSD_K_MAX_INPUT_LEN,
    GSD_K_MAX_OUTPUT_LEN,
    GSD_K_MAX_DATA_LEN,
    GSD_K_MODUL_OFFSET,
    GSD_K_MAX_DIAG_DATA_LEN,
    GSD_K_USER_PRM_DATA_LEN,
    GSD_K_MAX_USER_PRM_DATA_LEN,
    GSD_K_PRM_BLOCK_STRUCTURE_SUPP,
    GSD_K_IDENT_MAINTENANCE_SUPP,
    /* DP-V1 (GSD revision 3 on); from GSD_K_DPV1_FIRST on each needs DPV1_Slave = 1 */
    GSD_K_DPV1_SLAVE,
    GSD_K_C1_READ_WRITE_SUPP,
    GSD_K_DPV1_FIRST = GSD_K_C1_READ_WRITE_SUPP,
    GSD_K_C1_MAX_DATA_LEN,
    GSD_K_C1_RESPONSE_TIMEOUT,
    GSD_K_C1_READ_WRITE_REQUIRED,
    GSD_K_C2_READ_WRITE_SUPP,
    GSD_K_C2_MAX_DATA_LEN,
    GSD_K_C2_RESPONSE_TIMEOUT,
    GSD_K_C2_READ_WRITE_REQUIRED,
    GSD_K_C2_MAX_COUNT_CHANNELS,
    GSD_K_MAX_INITIATE_PDU_LENGTH,
    GSD_K_DPV1_DATA_TYPES,
    GSD_K_WD_BASE_1MS_SUPP,
    GSD_K_CHECK_CFG_MODE,
    GSD_K_DIAGNOSTIC_ALARM_SUPP,
    GSD_K_PROCESS_ALARM_SUPP,
    GSD_K_PULL_PLUG_ALARM_SUPP,
    GSD_K_STATUS_ALARM_SUPP,
    GSD_K_UPDATE_ALARM_SUPP,
    GSD_K_MANUFACTURER_SPECIFIC_ALARM_SUPP,
    GSD_K_EXTRA_ALARM_SAP_SUPP,
    GSD_K_ALARM_SEQUENCE_MODE_COUNT,
    GSD_K_ALARM_TYPE_MODE_SUPP,
    GSD_K_DIAGNOSTIC_ALARM_REQUIRED,
    GSD_K_PROCESS_ALARM_REQUIRED,
    GSD_K_PULL_PLUG_ALARM_REQUIRED,
    GSD_K_STATUS_ALARM_REQUIRED,
    GSD_K_UPDATE_ALARM_REQUIRED,
    GSD_K_MANUFACTURER_SPECIFIC_ALARM_REQUIRED,
    GSD_K_DPV1_LAST = GSD_K_MANUFACTURER_SPECIFIC_ALARM_REQUIRED,
    GSD_K_COUNT
} gsd_key_t;

/* The quoted strings kept (gsd_t.str, gsd_text()). */
typedef enum gsd_str_key {
    GSD_S_VENDOR_NAME = 0,
    GSD_S_MODEL_NAME,
    GSD_S_REVISION,
    GSD_S_HARDWARE_RELEASE,
    GSD_S_SOFTWARE_RELEASE,
    GSD_S_ORDER_NUMBER,
    GSD_S_IMPLEMENTATION_TYPE,
    GSD_S_COUNT
} gsd_str_key_t;

/* Where a parameter octet lives: the global User_Prm_Data or a module's part. */
#define GSD_GLOBAL (-1)

typedef struct gsd_rate {
    uint32_t baud;       /* 9600 .. 12000000 */
    bool supp;           /* <rate>_supp = 1 */
    uint32_t supp_line;  /* 0: the keyword is absent */
    uint16_t max_tsdr;   /* MaxTsdr_<rate> in bit times */
    uint32_t tsdr_line;  /* 0: absent */
} gsd_rate_t;

typedef struct gsd_module {
    uint32_t name;        /* offset in gsd_t.chars */
    uint16_t cfg_first;   /* index in gsd_t.cfg */
    uint16_t cfg_len;
    uint16_t prm_first;   /* index in gsd_t.module_prm: its Ext_User_Prm_Data_Const image */
    uint16_t prm_len;     /* Ext_Module_Prm_Data_Len, or the octets written if more */
    uint16_t ext_prm_len; /* Ext_Module_Prm_Data_Len as given */
    bool has_ext_prm_len;
    bool has_reference;
    uint32_t reference;   /* the module reference number (a bare number line, GSD rev. 3+) */
    bool preset;
    uint32_t line;
    uint32_t end_line;
} gsd_module_t;

/* Ext_User_Prm_Data_Const(offset) = octets, in the file or in a module. */
typedef struct gsd_const {
    int16_t module; /* GSD_GLOBAL or the module's index */
    uint16_t offset;
    uint16_t len;
    uint32_t line;
} gsd_const_t;

/* Ext_User_Prm_Data_Ref(offset) = number. */
typedef struct gsd_ref {
    int16_t module;
    uint16_t offset;
    uint16_t number; /* an ExtUserPrmData reference number */
    uint32_t line;
} gsd_ref_t;

typedef enum gsd_type {
    GSD_T_BIT = 0,  /* Bit(n) */
    GSD_T_BIT_AREA, /* BitArea(first-last) */
    GSD_T_UNSIGNED8,
    GSD_T_UNSIGNED16,
    GSD_T_UNSIGNED32,
    GSD_T_SIGNED8,
    GSD_T_SIGNED16,
    GSD_T_SIGNED32,
    GSD_T_NONE, /* no data type line (yet) */
} gsd_type_t;

/* ExtUserPrmData = number "name" ... EndExtUserPrmData. */
typedef struct gsd_prm_def {
    uint16_t number;
    uint32_t name;       /* offset in gsd_t.chars */
    gsd_type_t type;
    uint8_t bit_first;   /* Bit(n): n, n; BitArea(a-b): a, b */
    uint8_t bit_last;
    int64_t def;         /* the default */
    int64_t min, max;    /* the range (value_count 0), or the least and largest listed */
    uint16_t value_first; /* index in gsd_t.values */
    uint16_t value_count; /* 0: the range min..max; else the listed values */
    int32_t text_ref;    /* Prm_Text_Ref, -1: none */
    bool changeable;     /* Changeable (default 1) */
    bool visible;        /* Visible (default 1) */
    uint32_t line;
    uint32_t type_line;
} gsd_prm_def_t;

typedef struct gsd_text {
    int64_t value;
    uint32_t text; /* offset in gsd_t.chars */
} gsd_text_t;

/* PrmText = number, its Text(value) = "text" lines, EndPrmText. */
typedef struct gsd_text_table {
    uint16_t number;
    uint16_t first; /* index in gsd_t.texts */
    uint16_t count;
    uint32_t line;
} gsd_text_table_t;

typedef enum gsd_note_kind {
    GSD_NOTE_IGNORED = 0, /* a keyword this reader does not know (ignored, as the spec asks) */
    GSD_NOTE_REPEATED,    /* a keyword given twice: the later value is kept */
} gsd_note_kind_t;

typedef struct gsd_note {
    gsd_note_kind_t kind;
    uint32_t line;
    uint32_t first_line; /* REPEATED: where it was given first */
    char keyword[40];
} gsd_note_t;

typedef struct gsd {
    uint32_t header_line; /* #Profibus_DP */
    uint32_t lines;       /* lines read */

    uint32_t key[GSD_K_COUNT];
    uint32_t key_line[GSD_K_COUNT]; /* 0: absent */
    uint32_t str[GSD_S_COUNT];      /* offsets in chars */
    uint32_t str_line[GSD_S_COUNT];
    gsd_rate_t rate[GSD_RATE_COUNT];

    /* User_Prm_Data, then every global Ext_User_Prm_Data_Const, in file order */
    uint8_t user_prm[GSD_MAX_USER_PRM];
    uint16_t user_prm_written; /* octets reached by User_Prm_Data or a Const */
    uint32_t user_prm_data_line; /* User_Prm_Data (the revision 1 form), 0: absent */

    gsd_module_t modules[GSD_MAX_MODULES];
    size_t n_modules;
    uint8_t cfg[GSD_MAX_CFG_OCTETS];
    size_t n_cfg;
    uint8_t module_prm[GSD_MAX_MODULE_PRM];
    size_t n_module_prm;

    gsd_const_t consts[GSD_MAX_CONSTS];
    size_t n_consts;
    gsd_ref_t refs[GSD_MAX_REFS];
    size_t n_refs;
    gsd_prm_def_t defs[GSD_MAX_PRM_DEFS];
    size_t n_defs;
    int64_t values[GSD_MAX_VALUES];
    size_t n_values;
    gsd_text_table_t tables[GSD_MAX_TEXT_TABLES];
    size_t n_tables;
    gsd_text_t texts[GSD_MAX_TEXTS];
    size_t n_texts;

    gsd_note_t notes[GSD_MAX_NOTES];
    size_t n_notes;   /* kept */
    size_t notes_total; /* including those beyond GSD_MAX_NOTES */

    char chars[GSD_MAX_CHARS]; /* offset 0 is the empty string */
    size_t n_chars;
} gsd_t;

/* Reads a GSD file: 0, or -1 with "PATH:LINE: what" (or "PATH: what") in err. */
int gsd_parse_file(const char *path, gsd_t *out, char *err, size_t n);
/* The same for a text in memory; errors read "line LINE: what". */
int gsd_parse_text(const char *text, size_t len, gsd_t *out, char *err, size_t n);

/* The number of key k, false (value 0) when the file does not give it. */
bool gsd_key(const gsd_t *g, gsd_key_t k, uint32_t *value);
/* The keyword's name as the specification spells it ("Ident_Number"). */
const char *gsd_key_name(gsd_key_t k);
/* A kept string ("" when absent). */
const char *gsd_text(const gsd_t *g, gsd_str_key_t s);
/* A string of the pool (a module's or a parameter's name, a PrmText text). */
const char *gsd_chars(const gsd_t *g, uint32_t offset);

/* The rate's index 0..9 (9600 .. 12000000), -1 for a rate PROFIBUS does not have. */
int gsd_rate_index(uint32_t baud);
/* "9.6", "19.2", ..., "12M": the rate as in its keywords. */
const char *gsd_rate_name(size_t index);
/* The rate of index 0..9 in bit/s (0 for another index). */
uint32_t gsd_rate_baud(size_t index);
/* <rate>_supp = 1. */
bool gsd_supports_baud(const gsd_t *g, uint32_t baud);
/* MaxTsdr_<rate> in bit times; 0 when the rate is not supported or its MaxTsdr is absent. */
uint32_t gsd_max_tsdr_bits(const gsd_t *g, uint32_t baud);

/* The module's config octets. */
const uint8_t *gsd_module_cfg(const gsd_t *g, size_t module);
/* Its I/O lengths from its identifiers; false for malformed identifiers. */
bool gsd_module_io(const gsd_t *g, size_t module, uint16_t *in_len, uint16_t *out_len);
/* The module named name (exactly, else ignoring case), -1 if none. */
int gsd_find_module(const gsd_t *g, const char *name);
/* The ExtUserPrmData with this reference number, NULL if none. */
const gsd_prm_def_t *gsd_find_def(const gsd_t *g, uint16_t number);
/* The text of value v in PrmText table number, NULL if none. */
const char *gsd_prm_text(const gsd_t *g, int32_t table, int64_t v);

/* The User_Prm_Data a master sends by default in Set_Prm (after the 7 standard octets): the
 * global part (User_Prm_Data_Len long, else as far as its octets reach) from User_Prm_Data,
 * Ext_User_Prm_Data_Const and the defaults of Ext_User_Prm_Data_Ref, then the part of each
 * of the n configured modules (indices into modules) built the same way. Returns the length,
 * or -1 when it would exceed cap or GSD_MAX_USER_PRM or a module index is bad. */
int gsd_default_prm(const gsd_t *g, const size_t *modules, size_t n, uint8_t *out, size_t cap);

/* Octets a parameter of this type occupies (1 for Bit and BitArea). */
size_t gsd_def_octets(const gsd_prm_def_t *d);
/* The length of one part of the user parameters: GSD_GLOBAL's is User_Prm_Data_Len, a
 * module's Ext_Module_Prm_Data_Len; without them, as far as their octets reach. */
size_t gsd_part_len(const gsd_t *g, int module);

/* Writes value v of parameter d into an image at offset (its bits, big-endian for 16 and 32
 * bits), leaving the other bits; false when it does not fit into len octets. */
bool gsd_prm_put(const gsd_prm_def_t *d, int64_t v, uint8_t *image, size_t len, size_t offset);

typedef enum gsd_problem_code {
    GSD_P_MISSING = 0,   /* a mandatory keyword is absent */
    GSD_P_RATE,          /* a supported rate without MaxTsdr, no rate, a MaxTsdr below 11 */
    GSD_P_MODULE,        /* a module's identifiers malformed or longer than the Max_ rules */
    GSD_P_MODULES,       /* the station's modules against Modular_Station / Max_Module */
    GSD_P_PRM_LEN,       /* user parameter lengths against the octets defined */
    GSD_P_PRM_REF,       /* a Ref to no ExtUserPrmData, overlapping Refs, a bad Prm_Text_Ref */
    GSD_P_PRM_DEFAULT,   /* a default outside its range or list, min above max */
    GSD_P_DPV1,          /* DP-V1 keys against DPV1_Slave and each other */
    GSD_P_LIMIT,         /* a length beyond what the protocol carries */
    GSD_P_REPEATED,      /* a keyword given twice */
} gsd_problem_code_t;

typedef struct gsd_problem {
    gsd_problem_code_t code;
    uint32_t line; /* 0: the file as a whole */
    char text[160];
} gsd_problem_t;

/* The file checked against itself and the protocol's limits: returns the number of problems
 * (0: consistent) and writes the first max of them to out (out may be NULL when max is 0). */
size_t gsd_check(const gsd_t *g, gsd_problem_t *out, size_t max);

#endif
