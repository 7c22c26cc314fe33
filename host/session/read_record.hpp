#pragma once
// The read record (docs/session-output.md, "The read record"): what the
// session says about one object, defined once here and used everywhere a
// result goes: the TCP and serial result line, summary.json's object list and
// report.html's table. Besides the object's identity and counts, the record of
// its best sighting: when (UTC and the camera's clock), on which trigger
// (exposure counter, encoder counts), the ISO/IEC 15424 symbology identifier,
// the code's corners in the fused frame and its centre on the belt, the module
// size, the indicative quality, the blur used and its refinement, the decode
// time and the kept frame's file. NO-READs carry the frame part.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

#include "session/object_tracker.hpp"

namespace flutterscan::session {

/// \brief The results protocol's version: 2 added the record's fields to the
/// version 1 line (which it keeps unchanged, so a version 1 client still parses it).
inline constexpr int kResultsProtocolVersion = 2;

/// \brief `value` rounded to `decimals` decimal places, as the record and the
/// frame's log line give their numbers.
double rounded(double value, int decimals);

/// \brief `utc_ms` (ms since 1970) as ISO 8601 UTC with milliseconds:
/// "2026-11-25T17:05:29.123Z".
std::string iso8601_utc(std::int64_t utc_ms);

/// \brief The code part of a record: symbology identifier, corners, module size
/// and quality of one code read (also each `decoded` entry of session.jsonl).
nlohmann::json code_record(const reader::DecodedCode& code);

/// \brief A value and what it was read by: {"text", "format", "decoder", "pass"}
/// and "evidence" where it has any (reader/read_evidence.hpp; none: unconfirmed).
nlohmann::json value_json(const reader::DecodedCode& code);

/// \brief The record of one finished object.
nlohmann::json read_record(const ObjectResult& object);

/// \brief The record as the protocol's line (without '\n').
std::string result_line(const ObjectResult& object);

}  // namespace flutterscan::session
