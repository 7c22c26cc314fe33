// flutterscan: the command-line tool. Exit 0 on success, 1 when the work
// failed, 2 on bad usage or bad input, with the reason on stderr.

#include <CLI/CLI.hpp>

#include <iostream>

#include "app/cli_errors.hpp"
#include "app/commands.hpp"

int main(int argc, char** argv) {
  using namespace flutterscan::app;
  CLI::App app{"flutterscan: light-efficient flutter-shutter motion deblurring for conveyor belts"};
  app.name("flutterscan");
  app.set_version_flag("--version", FLUTTERSCAN_VERSION);
  app.require_subcommand(1);
  add_codes_command(app);
  add_simulate(app);
  add_deblur(app);
  add_bench(app);
  add_calibrate(app);
  add_scan(app);
  add_demo(app);
  add_cameras(app);
  add_replay(app);
  add_devices(app);
  add_device_command(app);
  add_flash(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 reports a missing subcommand before an unknown one: name the word it did not know.
    const auto rest = app.remaining(true);
    if (!rest.empty() && dynamic_cast<const CLI::RequiredError*>(&e) != nullptr)
      std::cerr << "flutterscan: unknown command '" << rest.front() << "'";
    else
      std::cerr << "flutterscan: " << e.what();
    std::cerr << "\n(run with --help for usage)\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << "flutterscan: " << e.what() << "\n";
    return 2;
  } catch (const RuntimeFailure& e) {
    std::cerr << "flutterscan: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
