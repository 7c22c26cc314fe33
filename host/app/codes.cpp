#include "app/commands.hpp"

namespace flutterscan::app {

void add_codes_command(CLI::App& app) {
  CLI::App* codes = app.add_subcommand(
      "codes",
      "LED codes: score them, search for better ones, plot their spectra, list the library");
  codes->require_subcommand(1);
  add_codes_score(*codes);
  add_codes_search(*codes);
  add_codes_plot(*codes);
  add_codes_list(*codes);
}

}  // namespace flutterscan::app
