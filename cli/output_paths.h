// Which output paths a command refuses, checked before the command does any work.
//
// CheckOutputPaths throws ident::InvalidArgument (one line naming the file, so the CLI exits 1) when
//   - an output is "-" (the commands write files only; their reports go to standard output),
//   - an existing output is not a regular file (a device such as /dev/full, a fifo, a directory),
//   - an output is one of the inputs (the same file by std::filesystem::equivalent, so also through a
//     symbolic or hard link),
//   - two outputs name the same file (equivalent if both exist, else equal after weakly_canonical).
// Empty paths (an option not given) are skipped. The files themselves are written by OutputFile
// (cli/output_file.h).
//
//   CheckOutputPaths({{"--trace", o.trace}, {"--plot", o.plot}}, {{"input data file", data_path}});
#pragma once

#include <string>
#include <vector>

namespace ident::cli {

struct NamedPath {
  std::string name;  // outputs: the option ("--trace"); inputs: a description ("input data file")
  std::string path;
};

void CheckOutputPaths(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs);

}  // namespace ident::cli
