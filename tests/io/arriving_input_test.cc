// OpenArrivingInput: a CsvReader on a pipe returns each row once its line is in the pipe, while the writer
// still holds the pipe open; before_wait runs before reads that may block; opening errors are one line.
#include "ident/io/arriving_input.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <future>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "common/error.h"
#include "ident/io/csv.h"
#include "tests/support/cli.h"

namespace ident::io {
namespace {

TEST(ArrivingInput, RowsArriveBeforeTheWriterClosesThePipe) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  std::atomic<bool> closed{false};
  std::promise<void> rows_read;
  std::future<void> rows_read_future = rows_read.get_future();
  // The writer keeps the pipe open until the reader has its rows (or, if the reader waits for the end of
  // the input, a deadlock guard of two minutes has passed: the checks below then fail, nothing hangs).
  std::thread writer([&] {
    const std::string text = "u,y\n1.5,2\n-3,4e-3\n";
    EXPECT_EQ(write(fds[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
    rows_read_future.wait_for(std::chrono::minutes(2));
    closed = true;
    close(fds[1]);
  });
  int waits = 0;
  CsvReader reader(OpenArrivingInput(fmt::format("/dev/fd/{}", fds[0]), [&] { ++waits; }), "pipe");
  EXPECT_EQ(reader.names(), (std::vector<std::string>{"u", "y"}));
  Eigen::VectorXd row(2);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(row, Eigen::Vector2d(1.5, 2));
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(row, Eigen::Vector2d(-3, 4e-3));
  EXPECT_FALSE(closed);  // both rows came while the writer still held the pipe
  EXPECT_GE(waits, 1);
  rows_read.set_value();
  EXPECT_FALSE(reader.Next(row));  // the writer closed: the end
  EXPECT_TRUE(closed);
  EXPECT_EQ(reader.rows_read(), 2);
  writer.join();
  close(fds[0]);
}

TEST(ArrivingInput, OpeningErrorsAreOneLine) {
  const std::string dir = ident::testing::TempDir();
  try {
    OpenArrivingInput(dir);
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot read '" + dir + "': it is a directory");
  }
  try {
    OpenArrivingInput(dir + "/absent.csv");
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot open '" + dir + "/absent.csv': No such file or directory");
  }
}

TEST(ArrivingInput, AFileReadsAsReadCsvReadsIt) {
  std::string text = "a,b\n";
  for (int i = 0; i < 30000; ++i) text += fmt::format("{},{}\n", i, 0.5 * i);  // several 64 KiB reads
  const std::string path = ident::testing::WriteFile("arriving.csv", text);
  CsvReader reader(OpenArrivingInput(path), path);
  const DataTable expected = ReadCsv(path);
  Eigen::VectorXd row(2);
  int r = 0;
  while (reader.Next(row)) {
    ASSERT_LT(r, expected.num_rows());
    EXPECT_EQ(row, expected.values.row(r).transpose()) << r;
    ++r;
  }
  EXPECT_EQ(r, 30000);
}

}  // namespace
}  // namespace ident::io
