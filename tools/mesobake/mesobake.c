/*
 * mesobake — the offline baker: meshes, skeletons and texture functions in,
 * one .meso file out. Deterministic (same inputs and options give the same
 * bytes: no timestamps, input paths recorded by base name) and atomic (the
 * output appears complete or not at all).
 *
 * CLI conventions: STYLE.md §8 (exit codes in cli_common.h).
 */
#include <stdio.h>
#include <string.h>

#include "batch.h"
#include "cli_util.h"

static const char* const usage_short =
    "Usage: mesobake <command> [options]\n"
    "\n"
    "Commands:\n"
    "  mesh     import a mesh (OBJ, OFF, PLY, STL, OM or DRC) as a MESH object\n"
    "  shell    build a fold-free shell (base mesh + directors) over a mesh\n"
    "  frusta   skin a skeleton (SWC, text, or one extracted from a mesh) with conical frusta\n"
    "  cells    fill a mesh with tiled cells: tile map, membership, normal and colour maps\n"
    "  batch    bake a manifest of jobs, cached, locally or on Slurm\n"
    "  pack     several .meso files into one, each object kept as its own\n"
    "\n"
    "Run 'mesobake --help' or 'mesobake <command> --help' for all options.\n";

static const char* const usage_full =
    "mesobake " MESO_VERSION_STRING " — bake fine surface detail into .meso files\n"
    "\n"
    "Usage: mesobake <command> [options]\n"
    "       mesobake --help | --version\n"
    "\n"
    "Commands:\n"
    "  mesh     import a mesh (OBJ, OFF, PLY, STL, OM or DRC) as a MESH object\n"
    "  shell    build a fold-free shell (base mesh + directors) over a mesh\n"
    "  frusta   skin a skeleton (SWC, text, or one extracted from a mesh) with conical frusta\n"
    "  cells    fill a mesh with tiled cells: tile map, membership, normal and colour maps\n"
    "  batch    bake a manifest of jobs, cached, locally or on Slurm\n"
    "  pack     several .meso files into one, each object kept as its own\n"
    "\n"
    MESOBAKE_HELP_EXIT_CODES
    "Outputs (-o, --report) are written atomically and together: a failed or\n"
    "interrupted bake (SIGINT, SIGTERM, SIGHUP) publishes nothing and leaves no\n"
    "temporary file. An output that is a symbolic link is written through to its\n"
    "target; a dangling link, directory, device, FIFO or socket is refused (exit 2).\n"
    "Every bake command takes --max-memory SIZE and refuses, before allocating, a\n"
    "request whose memory estimate is larger (default: half of physical memory).\n";

int main(int argc, char** argv)
{
    if (argc < 2) {
        fputs(usage_short, stderr);
        return MESO_EXIT_USAGE;
    }
    cli_signals_install();
    const char* cmd = argv[1];
    if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help")) {
        fputs(usage_full, stdout);
        return MESO_EXIT_OK;
    }
    if (!strcmp(cmd, "--version")) {
        printf("mesobake %s (format %d.%d, batch cache %d)\n", MESO_VERSION_STRING, MESO_FORMAT_MAJOR,
               MESO_FORMAT_MINOR, MESO_BATCH_CACHE_VERSION);
        return MESO_EXIT_OK;
    }
    if (!strcmp(cmd, "mesh"))
        return cmd_mesh(argc - 2, argv + 2);
    if (!strcmp(cmd, "shell"))
        return cmd_shell(argc - 2, argv + 2);
    if (!strcmp(cmd, "frusta"))
        return cmd_frusta(argc - 2, argv + 2);
    if (!strcmp(cmd, "cells"))
        return cmd_cells(argc - 2, argv + 2);
    if (!strcmp(cmd, "batch"))
        return cmd_batch(argc - 2, argv + 2);
    if (!strcmp(cmd, "pack"))
        return cmd_pack(argc - 2, argv + 2);
    if (cmd[0] == '-')
        return usage_error("unrecognized option '%s'", cmd);
    return usage_error("unknown command '%s'", cmd);
}
