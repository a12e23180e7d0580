// SweepFlags: the flags every dataset x resolution x method x threads sweep
// of bench/ takes (--data, --datasets, --res, --methods, --threads,
// --repeat, --max-range, --tum-max-range, --markdown), parsed once.
#pragma once

#include <string>

#include "../bench_data.hpp"
#include "argument_cursor.hpp"

namespace umbra_bench {

struct SweepFlags {
  umbra::bench::DatasetOptions data;
  std::string datasets;
  std::string resolutions = "0.05,0.02";
  std::string methods;
  std::string threads = "1";
  int repeat = 3;
  std::string markdown;  ///< where to write the table too (empty: nowhere)

  /// Takes `flag` and its value when it is one of the sweep's; false otherwise.
  bool take(const std::string& flag, ArgumentCursor& args) {
    if (flag == "--data") data.data_dir = args.value();
    else if (flag == "--datasets") datasets = args.value();
    else if (flag == "--res") resolutions = args.value();
    else if (flag == "--methods") methods = args.value();
    else if (flag == "--threads") threads = args.value();
    else if (flag == "--repeat") repeat = std::stoi(args.value());
    else if (flag == "--max-range") data.max_range = std::stod(args.value());
    else if (flag == "--tum-max-range") data.tum_max_range = std::stod(args.value());
    else if (flag == "--markdown") markdown = args.value();
    else return false;
    return true;
  }
};

}  // namespace umbra_bench
