#include "cli/csv_options.h"

#include <string>

namespace ident::cli {

void AddDelimiterOption(CLI::App& app, io::CsvOptions& csv) {
  app.add_option_function<std::string>(
         "--delimiter", [&csv](const std::string& text) { csv.delimiter = io::ParseDelimiter(text); },
         "Cell delimiter of the data file: ',', ';', tab, space (runs of spaces/tabs) or auto (detected; default)")
      ->check(CLI::Validator(
          [](std::string& text) {
            const bool known = text == "," || text == ";" || text == "tab" || text == "space" || text == "auto";
            return known ? std::string() : "'" + text + "' is not one of ',', ';', tab, space, auto";
          },
          "DELIMITER"));
}

}  // namespace ident::cli
