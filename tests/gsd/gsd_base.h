/* The GSD text the syntax and check tests extend: a consistent modular slave with one module.
 * What a test appends starts on line BASE_LINES + 1. */
#ifndef TESTS_GSD_BASE_H
#define TESTS_GSD_BASE_H

/* 21 lines: a consistent modular slave with one module. Extra lines start on line 22. */
#define BASE_LINES 21
static const char base[] =
    "#Profibus_DP\n"
    "GSD_Revision = 3\n"
    "Vendor_Name = \"V\"\n"
    "Model_Name = \"M\"\n"
    "Revision = \"R\"\n"
    "Ident_Number = 0x1234\n"
    "Protocol_Ident = 0\n"
    "Station_Type = 0\n"
    "Hardware_Release = \"H\"\n"
    "Software_Release = \"S\"\n"
    "Min_Slave_Intervall = 1\n"
    "Max_Diag_Data_Len = 6\n"
    "19.2_supp = 1\n"
    "MaxTsdr_19.2 = 60\n"
    "Modular_Station = 1\n"
    "Max_Module = 2\n"
    "Max_Input_Len = 8\n"
    "Max_Output_Len = 8\n"
    "Max_Data_Len = 16\n"
    "Module = \"1 byte in\" 0x10\n"
    "EndModule\n";

#endif
