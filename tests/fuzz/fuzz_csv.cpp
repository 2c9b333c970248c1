// CSV readers: the generic reader (text and numeric, finite or not), the clamping-data reader with the
// clamping-curve preprocessing (Algorithm II without the fit), the friction-map reader and the comparison of
// a table with itself (which must find no difference).
#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/identify/clamping_curve.hpp"
#include "jointsim/identify/friction_fit.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/report/compare.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  const std::string path = fuzz::writeInput("data/fuzz.csv", data, size);
  try {
    io::readCsvText(path);
  } catch (const Error& e) {
    fuzz::note(e);
  }
  try {
    io::readCsv(path, false);
  } catch (const Error& e) {
    fuzz::note(e);
  }
  try {
    const io::CsvTable table = io::readCsv(path, true);
    if (!report::compareTables(table, table).pass()) __builtin_trap();
  } catch (const Error& e) {
    fuzz::note(e);
  }
  try {
    identify::preprocessClampingCurve(identify::readClampingCsv(path, 2.0));
  } catch (const Error& e) {
    fuzz::note(e);
  }
  try {
    identify::readFrictionMap(path);
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
