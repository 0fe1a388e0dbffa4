#include "tools/structure_options.h"

#include "ident/common/error.h"

namespace ident::tools {

void StructureCliOptions::AddTo(CLI::App& app) {
  app.add_option("--output", output, "Output column y")->required();
  auto* input = app.add_option("--input", inputs, "Input column(s) u (comma-separated for several inputs)")
                    ->delimiter(',');
  auto* na_option = app.add_option("--na", na, "ARX order of the output polynomial (0: FIR)")->capture_default_str();
  auto* nb_option = app.add_option("--nb", nb, "Number of b coefficients (one value, or one per input)")
                        ->delimiter(',')
                        ->capture_default_str();
  auto* nk_option = app.add_option("--nk", nk, "Input delay in samples (one value, or one per input)")
                        ->delimiter(',')
                        ->capture_default_str();
  auto* regressors_option =
      app.add_option("--regressors", regressors, "Static regression on these columns (comma-separated)")
          ->delimiter(',')
          ->excludes(input)
          ->excludes(na_option)
          ->excludes(nb_option)
          ->excludes(nk_option);
  app.add_flag("--intercept", intercept, "Static regression: add an intercept (first parameter)")
      ->needs(regressors_option);
}

std::unique_ptr<DataSource> StructureCliOptions::MakeSource(const std::vector<std::string>& columns,
                                                            const std::string& source) const {
  if (!regressors.empty()) {
    models::StaticRegression regression{regressors, intercept};
    return MakeStaticSource(columns, output, regression, source);
  }
  IDENT_REQUIRE(!inputs.empty(), "give --input (ARX/FIR model) or --regressors (static regression)");
  const std::size_t m = inputs.size();
  auto per_input = [m](const std::vector<int>& v, const char* name) {
    IDENT_REQUIRE(v.size() == 1 || v.size() == m, "--{} has {} values; give one, or one per input ({})", name,
                  v.size(), m);
    return v.size() == m ? v : std::vector<int>(m, v[0]);
  };
  models::ArxStructure arx(na, per_input(nb, "nb"), per_input(nk, "nk"));
  return MakeArxSource(columns, output, inputs, arx, source);
}

}  // namespace ident::tools
