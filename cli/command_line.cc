#include "cli/command_line.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "common/error.h"

namespace ident::cli {

int StandardOutputError(int error) {
  std::cerr << "ident: error: cannot write to standard output: " << std::strerror(error ? error : EIO) << "\n";
  return kExitBadInput;
}

int RunCommandLine(int argc, char** argv) {
  CLI::App app{"ident: recursive, outlier-robust system identification", "ident"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "ident 0.1.0");
  AddFitCommand(app);
  AddDatasetsCommand(app);
  AddCompareCommand(app);
  AddOrdersCommand(app);
  AddPredictCommand(app);
  AddStreamCommand(app);
  AddMemsCommand(app);
  AddLogcondensCommand(app);
  AddSmoothCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line, like every other error. A first argument that is no option and no subcommand is named.
    std::string message = e.what();
    if (argc >= 2 && argv[1][0] != '-') {
      const std::string first = argv[1];
      bool known = false;
      for (const CLI::App* sub : app.get_subcommands({})) known = known || sub->check_name(first);
      if (!known) {
        message = "unknown subcommand '" + first + "' (known:";
        for (const CLI::App* sub : app.get_subcommands({})) message += " " + sub->get_name();
        message += ")";
      }
    }
    std::cerr << "ident: error: " << message << " (ident --help, ident SUBCOMMAND --help for usage)\n";
    return kExitUsage;
  } catch (const InvalidArgument& e) {
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const DataError& e) {
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::system_error& e) {  // fmt::print to stdout failing
    if (std::ferror(stdout)) return StandardOutputError(e.code().value());
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace ident::cli
