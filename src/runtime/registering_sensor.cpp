#include "rgbdtam/runtime/registering_sensor.hpp"

#include <cstring>

namespace rgbdtam {

RegisteringSensor::~RegisteringSensor() { stop(); }

void RegisteringSensor::init(LiveSensor* sensor, const Params& params) {
  RGBDTAM_ASSERT(params.depth_camera.register_to_colour,
                 "a sensor thread that registers nothing would hand over the sensor's buffers");
  sensor_ = sensor;
  registration_.init(params, DepthInColour::Buffer::kCallers);  // into the slots' depth
  for (int i = 0; i < FrameHandoff::kSlots; ++i) {
    handoff_.slot(i).gray.allocate(params.camera.width_px, params.camera.height_px);
    handoff_.slot(i).depth.allocate(params.camera.width_px, params.camera.height_px);
  }
}

size_t RegisteringSensor::bytes_needed(const Params& params) {
  const size_t pixels = static_cast<size_t>(params.camera.width_px) * params.camera.height_px;
  return DepthInColour::bytes_needed(params, DepthInColour::Buffer::kCallers) +
         FrameHandoff::kSlots * pixels * (sizeof(uint8_t) + sizeof(uint16_t));
}

Status RegisteringSensor::start(const ThreadPlacement& placement) {
  RGBDTAM_RETURN_IF_ERROR(sensor_->start(placement));
  running_ = true;
  thread_ = std::thread([this] { run(); });
  return place_thread(thread_, placement, "rgbdtam-sensor");
}

void RegisteringSensor::stop() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    quit_ = true;
  }
  state_changed_.notify_all();
  handoff_.stop();
  thread_.join();
  sensor_->stop();
}

void RegisteringSensor::close_stream() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    running_ = false;
  }
  handoff_.stop();  // out of any wait for the tracker
  std::unique_lock<std::mutex> lock(state_mutex_);
  state_changed_.wait(lock, [this] { return paused_; });
}

Status RegisteringSensor::open_stream() {
  RGBDTAM_RETURN_IF_ERROR(sensor_->reopen());
  handoff_.restart();
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    running_ = true;
  }
  state_changed_.notify_all();
  return Status::ok();
}

bool RegisteringSensor::wait_while_paused() {
  std::unique_lock<std::mutex> lock(state_mutex_);
  if (!running_ && !quit_) {
    paused_ = true;
    state_changed_.notify_all();
    state_changed_.wait(lock, [this] { return running_ || quit_; });
    paused_ = false;
  }
  return !quit_;
}

void RegisteringSensor::run() {
  while (wait_while_paused()) {
    SensorFrame frame;
    Status warning;
    const Status s = sensor_->next(&frame, &warning);
    sensor_dropped_.store(sensor_->dropped(), std::memory_order_relaxed);
    if (s.code() == StatusCode::kEndOfStream) {
      handoff_.end();
      std::lock_guard<std::mutex> lock(state_mutex_);
      running_ = false;  // nothing more to read unless reopened
      continue;
    }
    if (!s.is_ok()) {
      handoff_.publish_error(s);
      continue;
    }
    // The sensor's buffers are its own until its next frame: the grey image is kept here.
    FrameSlot& slot = handoff_.back();
    std::memcpy(slot.gray.data(), frame.gray, static_cast<size_t>(slot.gray.size()));
    frame.gray = slot.gray.data();
    registration_.apply_into(frame, slot.depth.data(), &slot.frame);
    slot.warning = warning;
    slot.arrival_ns = sensor_->arrival_ns();
    handoff_.publish();
  }
}

Status RegisteringSensor::next(SensorFrame* frame, Status* warning) {
  return handoff_.take(kFrameTimeoutMs, "sensor thread", frame, warning);
}

}  // namespace rgbdtam
