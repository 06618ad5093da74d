// ConeLOD CLI — the subcommands. Each takes the arguments after its name.
#pragma once

namespace conelod {
namespace cli {

int CmdGroup(int argc, char** argv);
int CmdCullCost(int argc, char** argv);
int CmdInfo(int argc, char** argv);
int CmdSimplify(int argc, char** argv);
int CmdPartition(int argc, char** argv);
int CmdProgressive(int argc, char** argv);
int CmdClusterShape(int argc, char** argv);
extern const char* kGroupUsage;
extern const char* kCullCostUsage;
extern const char* kInfoUsage;
extern const char* kSimplifyUsage;
int CmdFeatureSimplify(int argc, char** argv);
int CmdFeatureEdges(int argc, char** argv);
int CmdBudget(int argc, char** argv);
extern const char* kFeatureSimplifyUsage;
extern const char* kFeatureEdgesUsage;
extern const char* kBudgetUsage;
int CmdPartition(int argc, char** argv);
int CmdProgressive(int argc, char** argv);
extern const char* kPartitionUsage;
extern const char* kProgressiveUsage;
extern const char* kClusterShapeUsage;
int CmdLod(int argc, char** argv);
extern const char* kLodUsage;
int CmdServe(int argc, char** argv);
extern const char* kServeUsage;

}  // namespace cli
}  // namespace conelod
