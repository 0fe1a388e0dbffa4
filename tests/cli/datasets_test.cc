// The bundled datasets: checksums, the index behind `ident datasets`, and the command itself.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/dataset_index.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

TEST(Datasets, EveryCsvIsListedInSha256SumsAndMatchesIt) {
  std::set<std::string> listed;
  std::ifstream sums(DatasetPath("SHA256SUMS"));
  ASSERT_TRUE(sums) << "datasets/SHA256SUMS is missing";
  std::string hash, file;
  while (sums >> hash >> file) {
    EXPECT_EQ(hash.size(), 64u) << file;
    listed.insert(file);
  }
  std::set<std::string> present;
  for (const auto& entry : std::filesystem::directory_iterator(DatasetPath("")))
    if (entry.path().extension() == ".csv") present.insert(entry.path().filename().string());
  EXPECT_EQ(listed, present);
  EXPECT_EQ(present.size(), 11u);  // all records of ../shared/datasets
  // Independent check with coreutils' sha256sum.
  const std::string command = "cd '" + DatasetPath("") + "' && sha256sum --quiet -c SHA256SUMS > /dev/null 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << "checksum mismatch: run `cd datasets && sha256sum -c SHA256SUMS`";
}

TEST(Datasets, IndexCoversEveryFileAndItsSuggestedColumnsExist) {
  const std::vector<cli::DatasetInfo> index = cli::LoadDatasetIndex();
  std::set<std::string> files;
  for (const auto& d : index) {
    files.insert(d.file);
    const cli::CsvShape shape = cli::ReadCsvShape(d.path);
    std::vector<std::string> names;
    const Eigen::MatrixXd data = ReadCsvMatrix(d.path, &names);
    EXPECT_EQ(shape.columns, names) << d.name;
    EXPECT_EQ(shape.rows, data.rows()) << d.name;
    EXPECT_EQ(static_cast<std::uintmax_t>(shape.bytes), std::filesystem::file_size(d.path)) << d.name;
    auto has = [&names](const std::string& c) { return std::find(names.begin(), names.end(), c) != names.end(); };
    EXPECT_TRUE(has(d.structure.output)) << d.name << ": " << d.structure.output;
    for (const auto& c : d.structure.inputs) EXPECT_TRUE(has(c)) << d.name << ": " << c;
    for (const auto& c : d.structure.regressors) EXPECT_TRUE(has(c)) << d.name << ": " << c;
    EXPECT_TRUE(d.split > 0 && d.split <= 1) << d.name;
  }
  EXPECT_EQ(files.size(), 11u);
  EXPECT_EQ(index.size(), 11u);
  ASSERT_TRUE(cli::FindDataset("dryer"));
  EXPECT_EQ(cli::StructureArguments(cli::FindDataset("dryer")->structure), "--output y --input u --na 2 --nb 2 --nk 3");
  EXPECT_FALSE(cli::FindDataset("nonesuch"));
}

TEST(DatasetsCommand, ListsEveryRecordWithRowsColumnsSizeAndStructure) {
  const CliResult r = RunCli("datasets");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("dryer"), std::string::npos);
  // rows, size, columns and suggested structure of two records (rows counted independently above).
  EXPECT_NE(r.out.find("glassfurnace                  1247    96 kB  k,u1,u2,u3,y1,y2,y3,y4,y5,y6"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("--output y1 --input u1,u2,u3 --na 2 --nb 2,2,2 --nk 1,1,1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("silverbox_snls80mv          131072   4.5 MB"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--output stack_loss --regressors air_flow,water_temp,acid_conc --intercept"),
            std::string::npos);
}

TEST(DatasetsCommand, JsonHasOneObjectPerRecord) {
  const CliResult r = RunCli("datasets --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 11u);
  for (const auto& e : j) {
    for (const char* key : {"name", "file", "system", "ts", "rows", "columns", "bytes", "structure", "split"})
      EXPECT_TRUE(e.contains(key)) << key;
  }
  EXPECT_EQ(j[0]["name"], "dryer");
  EXPECT_EQ(j[0]["rows"], 1000);
  EXPECT_EQ(j[0]["columns"], (std::vector<std::string>{"t", "u", "y"}));
}

TEST(DatasetsCommand, BadInput) {
  EXPECT_EQ(RunCli("datasets --bogus").exit_code, 2);
  EXPECT_EQ(RunCli("datasets --help").exit_code, 0);
  setenv("IDENT_DATASETS", "/nonexistent", 1);  // inherited by the child: a missing index is a clear error
  const CliResult missing = RunCli("datasets");
  unsetenv("IDENT_DATASETS");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("cannot open the dataset index '/nonexistent/index.json'"), std::string::npos)
      << missing.err;
}

}  // namespace
}  // namespace ident::testing
