// The filter-model selector: the one list of the models a command can fly, their names on the
// command line and in outputs ("15", "24", "15c", "15t") and what each means. `sdins sil`, `replay`,
// `fsw` (--model), `diagnose` (--baseline), `montecarlo` (--models) and `paper` all parse and print
// these names through this header; each command accepts the subset it can fly.
//
// Which error-state layout flies a model is the harness's business (fsw/error_state.hpp): the flight
// software node flies 15 and 24 as Layout15Full / Layout24Full; the Monte Carlo 15 and 24 as those
// (or Layout15 / Layout24 with the GPS errors as white noise), 15c and 15t as Layout15Conv; the
// diagnosis takes 15 or 24 as its baseline inside LayoutDiag.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace fsw {

enum class FilterModel : std::uint8_t {
  k15,   ///< 15 states; the misalignments and scale factors as Schmidt consider states (consistent)
  k24,   ///< 24 states: 15 + 3 accelerometer and 6 gyro misalignments
  k15c,  ///< the conventional 15-state filter: misalignments ignored, the paper's sensor noise (untuned)
  k15t,  ///< the conventional 15-state filter tuned once: its gyro noise raised until its NEES is consistent
};

struct FilterModelInfo {
  FilterModel model;
  const char* name;         ///< command-line and output name
  const char* description;  ///< one line for --help
};

inline constexpr FilterModelInfo kFilterModels[] = {
    {FilterModel::k15, "15", "15-state, misalignments as consider states"},
    {FilterModel::k24, "24", "24-state, misalignments estimated"},
    {FilterModel::k15c, "15c", "conventional 15-state, misalignments ignored, untuned"},
    {FilterModel::k15t, "15t", "conventional 15-state, gyro noise tuned"},
};
inline constexpr std::size_t kFilterModelCount = sizeof(kFilterModels) / sizeof(kFilterModels[0]);

inline const FilterModelInfo& filter_model_info(FilterModel m) {
  for (const FilterModelInfo& i : kFilterModels)
    if (i.model == m) return i;
  return kFilterModels[0];
}
inline const char* to_string(FilterModel m) { return filter_model_info(m).name; }

/// "15", "24", "15c", "15t" -> model; false (out unchanged) for anything else.
inline bool parse_filter_model(const char* s, FilterModel& out) {
  if (s == nullptr) return false;
  for (const FilterModelInfo& i : kFilterModels) {
    if (std::strcmp(s, i.name) == 0) {
      out = i.model;
      return true;
    }
  }
  return false;
}

}  // namespace fsw
