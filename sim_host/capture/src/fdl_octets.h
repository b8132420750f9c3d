/* The FDL delimiters under the short names the capture parsers use, from the core's wire
 * definitions (protocol.md §A1.2), so the two can never disagree. */
#ifndef CAPTURE_FDL_OCTETS_H
#define CAPTURE_FDL_OCTETS_H

#include "dp_slave/fdl_wire.h"

#define SD1 FDL_SD1
#define SD2 FDL_SD2
#define SD3 FDL_SD3
#define SD4 FDL_SD4
#define SC FDL_SC
#define ED FDL_ED
#define ADDR_EXT FDL_ADDR_EXT

#endif
