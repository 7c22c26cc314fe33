#pragma once
// Where a latent looks like a code, whatever it is printed on. The label
// paper (find_paper_runs) finds white labels on a darker belt; a code printed
// on a carton, on cream or shadowed paper, or on a label dimmer than the
// light level expects has no such paper around it. A code is busy: high
// contrast well above the frame's noise, changing every few pixels in some
// direction. Text is busy too (and is read as nothing, cheaply); a carton's
// shading and an object's edge are not (one change across a cell).

#include <span>
#include <vector>

#include "imaging/image.hpp"
#include "reader/barcode_reader.hpp"

namespace flutterscan::reader {

/// \brief The busy regions of `latent` (the motion frame's; reflectance):
/// 16 x 16 px cells (every 4th row sampled, averaged with the row after it:
/// print is the same in both, the rows' deblurred noise is not) whose contrast (standard deviation
/// less the frame's noise, that of the flattest fifth of its cells that change at all along their
/// rows) is at least 0.04 and at least 1.5 times that noise, and whose mean absolute step between
/// neighbours (less the flattest cells') makes at least 1.5 changes between their darkest and
/// brightest every 16 px (an edge makes at most one; a code's modules more: bars up to about 5 px,
/// a matrix's modules up to about 10 px); such cells joined when they lie within one cell of each
/// other, a region kept when it holds at least 6; regions side by side along the rows within 128
/// px, sharing at least half the rows of the shorter, joined (a linear code's widest bars leave
/// cells between its busy ones that do not look busy). Each region's columns are [begin, end) and
/// its rows [across_begin, across_end), its busy cells' bounding box; `cut` when it touches the
/// first or last column.
std::vector<LabelRegion> find_code_regions(const imaging::Plane& latent);

/// \brief How much each of `regions` (of `latent`, motion frame) looks like a
/// linear code, 0 to 1: the correlation of the steps along the rows with the
/// same steps 8 rows on, or of the steps across the rows with those 8 columns
/// on, whichever is the greater (every 4th px each way). Bars run on in their
/// direction at any lean but the steepest, so their steps repeat 8 px on; a
/// line of text's strokes are a letter high, and the deblur's noise, each row
/// deblurred on its own, does not repeat from row to row. 0 where nothing
/// changes.
std::vector<double> bar_likeness(const imaging::Plane& latent,
                                 std::span<const LabelRegion> regions);

/// \brief Where to read: the paper runs, and the code regions that do not lie
/// inside one of them (a run whose rows were not measured spans every row).
std::vector<LabelRegion> regions_to_read(std::span<const LabelRegion> paper,
                                         std::span<const LabelRegion> code);

}  // namespace flutterscan::reader
