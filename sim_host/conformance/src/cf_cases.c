/* The suite: the groups' case tables joined in report order (cf_all_cases). */
#include <string.h>

#include "conformance/cf.h"
#include "conformance/cf_cases.h"

static const char *const group_names[] = {"GSD", "FDL", "DP state machine", "Timing", "DP-V1"};

const char *const *cf_group_names(size_t *n)
{
    *n = sizeof group_names / sizeof group_names[0];
    return group_names;
}

typedef struct group_table {
    const cf_case_t *cases;
    const size_t *count;
} group_table_t;

size_t cf_all_cases(cf_case_t *out, size_t cap)
{
    const group_table_t tables[] = {CF_CASE_TABLES};
    size_t n = 0;
    for (size_t t = 0; t < sizeof tables / sizeof tables[0]; t++) {
        if (tables[t].cases == NULL) {
            continue;
        }
        for (size_t i = 0; i < *tables[t].count && n < cap; i++) {
            out[n++] = tables[t].cases[i];
        }
    }
    return n;
}
