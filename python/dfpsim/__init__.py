"""dfpsim: a client for the control API of dfp-sim (docs/api.md), the simulated SEW DFP21B
PROFIBUS-DP option card and its MOVIDRIVE, for test scripts and commissioning checklists.

    from dfpsim import DfpSim, wait_until

    with DfpSim.slave_and_master(address=4) as bus:
        drive, plc = bus.slave.card(4), bus.master.master()
        wait_until(lambda: drive.dp_state == "Data_Exch", what="data exchange")
        plc.write_param(4, "P100", "FIELDBUS")
        plc.set_po(4, [0x0006, 1500])
        wait_until(lambda: drive.speed_actual_rpm >= 299.5, timeout=3)

Standard library only.
"""

from .client import API, PARAM_VIAS, Card, Client, Master, ParamResult, parse_sse
from .errors import ApiError, AuthError, DfpSimError, ParamError, TlsError
from .process import DfpSim, SlaveAndMaster, find_dfp_sim, free_port
from .wait import wait_for, wait_until

__version__ = "0.1.0"

__all__ = [
    "API", "ApiError", "AuthError", "Card", "Client", "DfpSim", "DfpSimError", "Master",
    "PARAM_VIAS", "ParamError", "ParamResult", "SlaveAndMaster", "TlsError", "find_dfp_sim",
    "free_port", "parse_sse", "wait_for", "wait_until",
]
