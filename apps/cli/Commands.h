// Commands: `facet` subcommands implemented in their own files.
#pragma once

#include <string>
#include <vector>

namespace facet {

// A command line that does not make sense, thrown by a command (and by
// CompileFlags.h): main prints `message` with the usage text of every
// command, and exits 2.
struct UsageError {
    std::string message;
};

// facet eval FILE --in IN.csv [--out OUT.csv] ...  (EvalCommand.cpp): the BRDF
// for each CSV row. Throws UsageError.
int cmdEval(const std::vector<std::string>& args);

// facet verify FILE... (VerifyCommand.cpp): hard cases, backend agreement and
// physics checks. Returns the process exit code (0 ok, 1 a check failed,
// 2 usage, 65 a material file error).
int cmdVerify(const std::vector<std::string>& args);

// facet lut FILE [--material NAME] -o TABLES.exr  (LutCommand.cpp)
int cmdLut(const std::vector<std::string>& args);

// facet bench FILE... [--out DIR] [--json] [--quick]  (BenchCommand.cpp, bench/)
int cmdBench(const std::vector<std::string>& args);

// facet render FILE -o OUT [--plot lobe|ndf|pdf] ...  (RenderCommand.cpp, apps/preview/)
int cmdRender(const std::vector<std::string>& args);

// facet sample FILE --wo X,Y,Z [-n N] [--out OUT.csv] [--seed S]  (SampleCommand.cpp)
int cmdSample(const std::vector<std::string>& args);

// facet build FILE -o OUT.o [--header OUT.h] [--target T] ...  (BuildCommand.cpp, runtime/Aot.h)
int cmdBuild(const std::vector<std::string>& args);

}  // namespace facet
