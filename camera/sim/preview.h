// Pictures of a simulation, so a person can see that it looks right: every `every`-th mask
// tick a PNG of three panels (intensity, mask over intensity, the events of the last frame
// interval as red ON / blue OFF dots with the projected skeleton), and at the end a contact
// sheet of event panels spread over the run. Passes everything on to `next`.
#pragma once
#include <string>
#include <vector>

#include "camera/sim/simulator.h"

namespace yelan::camera::sim {

class PreviewSink final : public SimSink {
 public:
  PreviewSink(const std::string& dir, const Simulator& sim, int every = 5, SimSink* next = nullptr);
  void events(std::span<const Event> ev) override;
  void label(const Label& l) override;
  void mask(std::int64_t t_us, const RenderedFrame& frame) override;
  // Writes contact_sheet.png (up to 12 event panels, 4 per row); returns the paths written.
  std::vector<std::string> finish();

 private:
  std::string dir_;
  const Simulator& sim_;
  int every_;
  SimSink* next_;
  int w_, h_;
  std::int64_t ticks_ = 0;
  std::vector<std::uint16_t> on_, off_;
  struct Panel {
    std::int64_t t_us;
    std::vector<std::uint8_t> rgb;
  };
  std::vector<Panel> kept_;
  int keep_stride_ = 1;
  std::vector<std::string> written_;
};

// Draws the 13-joint skeleton (SPEC edges) of camera-frame joints into an RGB image.
void draw_skeleton(std::vector<std::uint8_t>& rgb, int width, int height, const CameraModel& cam, const Label& l);

}  // namespace yelan::camera::sim
