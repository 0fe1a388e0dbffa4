// ident fit — placeholder until the fit workflow lands.
#include "tools/commands.h"

namespace ident::tools {
void AddFitCommand(CLI::App& app) {
  app.add_subcommand("fit", "Fit a model to recorded data with a recursive estimator");
}
}  // namespace ident::tools
