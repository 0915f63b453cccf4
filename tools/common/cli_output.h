/* cli_output.h — how mesobake and mesoinspect publish their output files.
 *
 * Every file a run writes is staged: meso_output_open makes a temporary
 * file beside its destination (following a symbolic link to its target,
 * refusing anything that is not a regular file), the run writes it, and only
 * when every output of the run is complete does cli_outputs_publish rename
 * them into place, in the order staged. A run that fails calls
 * cli_outputs_discard and publishes nothing. While a temporary file exists
 * it is registered with the handler cli_signals_install puts on SIGINT,
 * SIGTERM and SIGHUP: the handler unlinks it and re-raises the signal, so an
 * interrupted run leaves the old files as they were and no temporary file.
 *
 * Test hook: when the environment variable MESO_TEST_HOLD_OUTPUTS is set,
 * cli_outputs_publish waits for a signal (pause) before renaming anything,
 * with every temporary file complete. Tests use it to send a signal at a
 * known moment instead of racing a timer; nothing else sets it.
 */
#ifndef MESO_CLI_OUTPUT_H
#define MESO_CLI_OUTPUT_H

#include "meso_file.h"

/* The most outputs one run stages (the .meso file and the --report file). */
#define CLI_MAX_OUTPUTS 4

/* Install the cleanup handler on SIGINT, SIGTERM and SIGHUP (a signal the
 * program inherited as ignored, as under nohup, stays ignored). */
void cli_signals_install(void);

/* Stage an output: the temporary file is created and registered with the
 * signal handler; *out is open for writing (meso_output_write, or by its
 * `temp` name). A refused destination is MESO_ERR_IO with issue
 * MESO_ISSUE_IO_DESTINATION; a file named by two outputs INVALID_ARG. After
 * a failed write, call cli_outputs_discard. */
meso_result cli_output_stage(const char* path, meso_output** out, meso_error* err);
/* Publish every staged output, in order. On failure the ones not yet
 * renamed are removed and *err names the one that failed. */
meso_result cli_outputs_publish(meso_error* err);
/* Remove every staged output's temporary file; publish nothing. */
void cli_outputs_discard(void);

#endif
