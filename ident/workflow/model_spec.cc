#include "ident/workflow/model_spec.h"

#include "common/error.h"

namespace ident::workflow {

std::unique_ptr<DataSource> ModelSpec::MakeSource(const std::vector<std::string>& columns,
                                                  const std::string& source) const {
  // The cleaning options are checked whatever the structure: a bad value is an error, not ignored.
  IDENT_REQUIRE(clean_regressors == "on" || clean_regressors == "off", "--clean-regressors '{}': need on or off",
                clean_regressors);
  IDENT_REQUIRE(nc >= 0 && nd >= 0 && nf >= 0, "--nc {}, --nd {}, --nf {}: orders must be >= 0", nc, nd, nf);
  models::OutputCleaningOptions clean = cleaning;
  clean.enabled = clean_regressors == "on";
  const std::string error = clean.Validate();
  IDENT_REQUIRE(error.empty(), "--clean-clip/--clean-gross: {}", error);
  if (!regressors.empty()) {
    IDENT_REQUIRE(inputs.empty(), "give --input (ARX/FIR model) or --regressors (static regression), not both");
    IDENT_REQUIRE(!polynomial(), "--nc/--nd/--nf describe a dynamic model; they do not apply to --regressors");
    models::StaticRegression regression{regressors, intercept};
    return MakeStaticSource(columns, output, regression, source);
  }
  IDENT_REQUIRE(!intercept, "--intercept needs --regressors (a static regression)");
  IDENT_REQUIRE(!inputs.empty(), "give --input (ARX/FIR model) or --regressors (static regression)");
  const std::size_t m = inputs.size();
  auto per_input = [m](const std::vector<int>& v, const char* name) {
    IDENT_REQUIRE(v.size() == 1 || v.size() == m, "--{} has {} values; give one, or one per input ({})", name, v.size(),
                  m);
    return v.size() == m ? v : std::vector<int>(m, v[0]);
  };
  IDENT_REQUIRE(recursion == "rplr" || recursion == "rpem", "--recursion '{}': need rplr or rpem", recursion);
  IDENT_REQUIRE(recursion == "rplr" || polynomial(), "--recursion rpem needs an ARMAX (--nc), OE (--nf) or BJ model");
  if (polynomial()) {
    const models::PolynomialStructure structure(na, per_input(nb, "nb"), per_input(nk, "nk"), nc, nd, nf);
    return MakePolynomialSource(
        columns, output, inputs, structure, source, clean,
        recursion == "rpem" ? models::Recursion::kPredictionError : models::Recursion::kPseudoLinear);
  }
  models::ArxStructure arx(na, per_input(nb, "nb"), per_input(nk, "nk"));
  return MakeArxSource(columns, output, inputs, arx, source, clean);
}

OutlierDecision ModelSpec::Decision() const {
  OutlierDecision decision{clean_below};
  const std::string error = decision.Validate();
  IDENT_REQUIRE(error.empty(), "--clean-below: {}", error);
  return decision;
}

}  // namespace ident::workflow
