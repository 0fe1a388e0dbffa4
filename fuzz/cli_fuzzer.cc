// libFuzzer target: the whole command line in-process (cli::RunCommandLine) on a small data file and an
// argument vector built from the input (properties in fuzz/cli_property.h).
#include "fuzz/cli_property.h"
#include "fuzz/fuzz_util.h"

IDENT_FUZZ_ENTRY(ident::fuzz::CliProperty)
