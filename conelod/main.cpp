// ConeLOD command-line tool: the same core as the MeshLab plugin, with no X server.
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include "cli_common.h"
#include "commands.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* const* usage;
};

const Command kCommands[] = {
    {"group", conelod::cli::CmdGroup, &conelod::cli::kGroupUsage},
    {"cull-cost", conelod::cli::CmdCullCost, &conelod::cli::kCullCostUsage},
    {"info", conelod::cli::CmdInfo, &conelod::cli::kInfoUsage},
    {"simplify", conelod::cli::CmdSimplify, &conelod::cli::kSimplifyUsage},
    {"feature-simplify", conelod::cli::CmdFeatureSimplify, &conelod::cli::kFeatureSimplifyUsage},
    {"feature-edges", conelod::cli::CmdFeatureEdges, &conelod::cli::kFeatureEdgesUsage},
    {"budget", conelod::cli::CmdBudget, &conelod::cli::kBudgetUsage},
    {"partition", conelod::cli::CmdPartition, &conelod::cli::kPartitionUsage},
    {"progressive", conelod::cli::CmdProgressive, &conelod::cli::kProgressiveUsage},
    {"cluster-shape", conelod::cli::CmdClusterShape, &conelod::cli::kClusterShapeUsage},
    {"lod", conelod::cli::CmdLod, &conelod::cli::kLodUsage},
    {"serve", conelod::cli::CmdServe, &conelod::cli::kServeUsage},
};

void PrintUsage(FILE* out) {
  std::fprintf(out, "usage: conelod COMMAND [arguments]   (conelod COMMAND --help for details)\n\ncommands:\n");
  for (const auto& c : kCommands) std::fprintf(out, "%s", *c.usage);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    PrintUsage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 1 : 0;
  }
  for (const auto& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    for (int i = 2; i < argc; ++i)
      if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
        std::printf("%s", *c.usage);
        return 0;
      }
    // Outputs are checked before the work starts, so a bad path never costs a long run.
    const std::string outputError = conelod::cli::CheckOutputs(c.name, argc - 2, argv + 2);
    if (!outputError.empty()) {
      std::fprintf(stderr, "conelod: %s\n", outputError.c_str());
      return conelod::cli::kIoError;
    }
    try {
      return c.run(argc - 2, argv + 2);
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr,
                   "conelod: out of memory (the mesh or an option such as --samples is too large for this machine)\n");
      return conelod::cli::kOutOfMemory;
    }
  }
  std::fprintf(stderr, "conelod: unknown command '%s'\n", argv[1]);
  PrintUsage(stderr);
  return 1;
}
