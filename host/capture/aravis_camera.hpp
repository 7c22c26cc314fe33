#pragma once
// "aravis:NAME": GenICam cameras (GigE Vision, USB3 Vision) through Aravis 0.8.
// NAME is Aravis's device id (arv_get_device_id: "Vendor-Model-Serial", or
// "Fake_1" for Aravis's in-process fake camera once the "Fake" interface is
// enabled; `aravis:fake` enables it and opens Fake_1).
//
// configure(): pixel format (RGGB Bayer 8/10/12/16, Mono 8/10/12/16, RGB8,
// BGR8), region, ExposureAuto and GainAuto Off, BalanceWhiteAuto Off, gamma
// 1 / GammaEnable and LUTEnable false where the camera has them, exposure
// time, gain, frame rate; trigger: TriggerMode On with TriggerSource Line0
// (the LED controller in master mode) or Software, or TriggerMode Off. Every
// value is read back. start() refuses while an automatic still reads as on.
// Frames carry the GenICam frame id as sequence and the camera's timestamp;
// gaps in frame ids and buffers that did not arrive whole count as dropped.

#include <memory>
#include <optional>
#include <string>

#include "capture/camera_source.hpp"

namespace flutterscan::capture {

/// \brief An Aravis camera by device id (see above).
std::unique_ptr<CameraSource> make_aravis_camera(const std::string& device_id);

/// \brief Tests only: makes Aravis's fake camera behind `camera` (started) produce
/// one frame that never reaches the stream, as a frame lost on the wire would:
/// the next frame's id jumps by two. Error if `camera` is not a started Aravis fake.
std::string lose_one_fake_frame(CameraSource& camera);

/// \brief Tests only: whether Aravis's fake camera behind `camera` has a software
/// trigger pending (and acknowledges it). Aravis 0.8.26's in-process fake
/// records TriggerSoftware but keeps streaming at its frame rate, so this is
/// how a test sees that the trigger reached the camera. nullopt if not a fake.
std::optional<bool> take_fake_software_trigger(CameraSource& camera);

}  // namespace flutterscan::capture
