// Input that is read as it arrives: standard input, a pipe or a FIFO fed by a running process.
//
// OpenArrivingInput returns an istream over a file descriptor whose buffer hands over, from each
// read(2), whatever the descriptor holds, so a CsvReader on it returns a row as soon as its line has
// arrived instead of waiting for a full chunk or the end of the input (std::cin and std::ifstream fill
// their reads to the size asked for). The end of the input is a read that returns nothing (the writer
// closed the pipe, the end of a regular file). `before_wait`, if set, runs before every read(2) that
// may block: `ident stream` flushes its output there, so a consumer has every line for the rows
// received before the program waits for more. A failing read(2) throws std::runtime_error with the
// system's message (CsvReader turns it into "cannot read 'x': ...").
//
// Example:
//   ident::io::CsvReader reader(ident::io::OpenArrivingInput("-"), "standard input");
//   Eigen::VectorXd row(reader.num_columns());
//   while (reader.Next(row)) { ... }   // each row as soon as its line is complete
#pragma once

#include <functional>
#include <istream>
#include <memory>
#include <string>

namespace ident::io {

// kStandardInput ("-") reads descriptor 0 (left open); any other path is opened read-only (a FIFO:
// this waits until a writer opens it). Throws DataError "cannot open 'x': ..." or "cannot read 'x': it is
// a directory".
std::unique_ptr<std::istream> OpenArrivingInput(const std::string& path, std::function<void()> before_wait = {});

}  // namespace ident::io
