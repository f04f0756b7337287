-- The driver body; the parameters and tables above it are generated.

local MNT1_TYPE = Parameter("MNT1_TYPE")    -- should be 9:Scripting

-- timing (milliseconds of millis())
local INTERVAL_MS = {
  INIT = 3000,              -- retry the set-up at this interval
  UPDATE = 10,              -- run at 100 Hz
  TARGET = 50,              -- gimbal_control every 50 ms, as the protocol document recommends
  ATTITUDE = 100,           -- UAV attitude to the gimbal at 10 Hz
  POSITION = 200,           -- UAV GPS and altitude to the gimbal at 5 Hz
  LOCATION = 2000,          -- angles to a location target at most this often ...
  FEEDBACK_TIMEOUT = 2000,  -- no feedback this long (4 messages): the gimbal is silent
  SEGMENT_TIMEOUT = 200,    -- a feedback message's segments come within this
  REPORT = 5000,            -- at most one problem report to the GCS this often
}
local SETTINGS = {
  LOCATION_STEP_DEG = 1.0,  -- ... and when they moved at least this much
  WRITE_TIMEOUT_US = 10000, -- write_frame waits at most 10 ms (its timeout is in microseconds)
  CAN_BUFFER_LEN = 25,      -- frames buffered between updates (1 to 25)
  TRACK_POINT_SIZE = 512,   -- a tracked point gets a box this big (image coordinates)
  MOUNT_INSTANCE = 0,       -- the first mount (MNT1)
  CAMERA_INSTANCE = 0,      -- the first camera (CAM1)
  ALL_ID_BITS = -1,         -- add_filter's mask: every bit of the id, its flags too
}
local MAV_SEVERITY = {EMERGENCY=0, ALERT=1, CRITICAL=2, ERROR=3, WARNING=4, NOTICE=5, INFO=6, DEBUG=7}

-- the CANFrame ids: ArduPilot marks an extended (29-bit) CAN ID with bit 31
local FRAME_ID = {}
do
  local extended = uint32_t(1) << 31
  FRAME_ID.CONTROL = uint32_t(PROTOCOL.control_id) | extended
  FRAME_ID.FEEDBACK = uint32_t(PROTOCOL.feedback_id) | extended
  FRAME_ID.GPS = uint32_t(STATUS.gps.id) | extended
  FRAME_ID.ALTITUDE = uint32_t(STATUS.altitude.id) | extended
  FRAME_ID.ATTITUDE = uint32_t(STATUS.attitude.id) | extended
end

-- state
local driver = nil                      -- the scripting CAN buffer
local state = {
  initialised = false,
  started_ms = uint32_t(0),
  rates_moving = false,                 -- gimbal_control with a speed was the last rate sent
  sent_pitch = nil,                     -- raw values of the last specified_angle per axis
  sent_yaw = nil,
  sent_yaw_frame = nil,
  location_pitch_deg = nil,             -- angles last sent for a location target
  location_yaw_deg = nil,
  last_location_ms = uint32_t(0),
  last_report_ms = uint32_t(0),
  reported_once = false,
}
local camera_state = {seen = false, pic_count = 0, recording = false, zoom_type = 0, zoom_value = 0,
  focus_type = 0, focus_value = 0, track_type = 0, track = {0, 0, 0, 0}}

-- feedback reassembly
local feedback = {
  segments = {},                        -- bytes of the message being reassembled
  count = 0,                            -- segments gathered
  last_segment_ms = uint32_t(0),
  last_message_ms = uint32_t(0),
  seen = false,
  lost = false,
}

-- counters
local counts = {read = 0, sent = 0, write_fails = 0, ignored = 0, ok = 0, crc = 0, cut = 0,
  unreported_crc = 0, unreported_cut = 0}

-- a timer on millis(), due every `period` ms on a fixed schedule; time is compared as
-- uint32_t (never converted to a Lua integer), right across millis()'s wrap at 2^32.
-- After a hold-up it makes up at most `catch_up` periods, one per update
local function new_timer(period, catch_up)
  return {period = period, catch_up = catch_up, last = nil}
end

local timers = {
  target = new_timer(INTERVAL_MS.TARGET, 1),
  attitude = new_timer(INTERVAL_MS.ATTITUDE, 5),
  position = new_timer(INTERVAL_MS.POSITION, 5),
  debug = new_timer(INTERVAL_MS.REPORT, 1),
}

-- true when `timer` is due at `now` (at once the first time); it then counts from when it
-- was due, not from now, so late updates do not slow the schedule (further behind than it
-- makes up: from now)
local function timer_due(timer, now)
  if timer.last == nil then
    timer.last = now
    return true
  end
  if now - timer.last < timer.period then
    return false
  end
  timer.last = timer.last + timer.period
  if now - timer.last >= timer.period * timer.catch_up then
    timer.last = now
  end
  return true
end

local function wrap_360(angle)
  local res = math.fmod(angle, 360.0)
  if res < 0 then
    res = res + 360.0
  end
  return res
end

local function wrap_180(angle)
  local res = wrap_360(angle)
  if res > 180 then
    res = res - 360
  end
  return res
end

-- the protocol's encoding and decoding: fields to bytes and back, CRC, frames
local codec = {}

-- `value` * `scale` rounded to the nearest integer, a tie to the even one (Python's
-- round()), exact in 32-bit floats: the product's rounding error (Dekker's split of `value`
-- into two 12-bit halves) decides what the rounded product cannot
function codec.round_scaled(value, scale)
  local product = value * scale
  if product ~= product then
    return 0                              -- not a number: the field's zero point
  end
  local whole = math.floor(product)
  if whole == product then                -- whole already (as is every 32-bit float >= 2^23)
    return whole
  end
  local c = 4097.0 * value
  local high = c - (c - value)
  local err = (high * scale - product) + (value - high) * scale
  local rest = (product - whole) - 0.5    -- exact
  if rest > -err or (rest == -err and whole % 2 == 1) then
    whole = whole + 1
  end
  return whole
end

-- a raw integer kept inside the field's (the document's) range
function codec.clamp_raw(field, raw)
  if raw < field.min then
    return field.min
  elseif raw > field.max then
    return field.max
  end
  return math.tointeger(raw) or raw
end

-- a physical value as the integer a field carries: scaled, rounded and kept inside the
-- document's range (a value outside it is never sent)
function codec.raw_value(field, value)
  return codec.clamp_raw(field, codec.round_scaled(value, field.div / field.mul))
end

-- write a raw integer into a byte table (1-based) at the field's offset, little-endian,
-- kept inside the document's range
function codec.put_raw(data, field, raw)
  raw = codec.clamp_raw(field, raw)
  for i = 0, field.size - 1 do
    data[field.off + 1 + i] = (raw >> (8 * i)) & 0xFF
  end
end

function codec.put(data, field, value)
  codec.put_raw(data, field, codec.raw_value(field, value))
end

-- the raw integer of a field of a byte table (1-based); a signed field's sign extended
-- (a 4-byte field is a 32-bit Lua integer: ArduPilot's)
function codec.get_raw(data, field)
  local raw = 0
  for i = field.size - 1, 0, -1 do
    raw = (raw << 8) | data[field.off + 1 + i]
  end
  if field.signed then
    local sign = 1 << (8 * field.size - 1)
    raw = (raw ~ sign) - sign
  end
  return raw
end

-- a field of a byte table as its physical value
function codec.get(data, field)
  return codec.get_raw(data, field) * field.mul / field.div
end

function codec.crc16(data, count)
  local crc = PROTOCOL.crc_init
  for i = 1, count do
    crc = (crc >> 8) ~ CRC_TABLE[((crc ~ data[i]) & 0xFF) + 1]
  end
  return crc
end

local function send_frame(frame_id, data)
  local frame = CANFrame()
  frame:id(frame_id)
  for i = 1, 8 do
    frame:data(i - 1, data[i])
  end
  frame:dlc(8)
  if driver:write_frame(frame, SETTINGS.WRITE_TIMEOUT_US) then
    counts.sent = counts.sent + 1
  else
    counts.write_fails = counts.write_fails + 1
  end
end

-- a command's 8 CAN bytes: S_ID, CMD, then its fields (labels are given as their codes)
function codec.encode_command(name, values)
  local command = COMMANDS[name]
  local data = {command.s_id, command.cmd, 0, 0, 0, 0, 0, 0}
  for field_name, value in pairs(values) do
    local field = command.fields[field_name]
    if field.labels then
      codec.put_raw(data, field, value)
    else
      codec.put(data, field, value)
    end
  end
  return data
end

local function send_command(name, values)
  send_frame(FRAME_ID.CONTROL, codec.encode_command(name, values))
end

-- set-up: the scripting CAN driver chosen by VSH_CAN_DRV, filtered to the feedback's ID
local function init()
  if MNT1_TYPE:get() ~= 9 then
    gcs:send_text(MAV_SEVERITY.CRITICAL, "VSH: set MNT1_TYPE=9")
    return
  end
  local which = VSH_CAN_DRV:get()
  if which == 1 then
    driver = CAN:get_device(SETTINGS.CAN_BUFFER_LEN)
  elseif which == 2 then
    driver = CAN:get_device2(SETTINGS.CAN_BUFFER_LEN)
  else
    gcs:send_text(MAV_SEVERITY.CRITICAL, "VSH: set VSH_CAN_DRV to 1 or 2")
    return
  end
  if not driver then
    gcs:send_text(MAV_SEVERITY.CRITICAL, string.format("VSH: no scripting CAN driver %d", which))
    return
  end
  if not driver:add_filter(SETTINGS.ALL_ID_BITS, FRAME_ID.FEEDBACK) then
    gcs:send_text(MAV_SEVERITY.WARNING, "VSH: no CAN filter: reading every frame")
  end
  state.initialised = true
  state.started_ms = millis()
  feedback.last_message_ms = state.started_ms
  gcs:send_text(MAV_SEVERITY.INFO, "VSH: mount driver started")
end

-- the attitude of a good attitude message (pitch, yaw of the yaw motor, body frame)
local function message_attitude(message)
  local fields = FEEDBACK[message[3]].fields
  return codec.get(message, fields.pitch_deg), wrap_180(codec.get(message, fields.motor_yaw_deg))
end

-- a good feedback message: report the attitude to the mount library at once
local function handle_message(message)
  counts.ok = counts.ok + 1
  if FEEDBACK[message[3]].name ~= "attitude" then
    return
  end
  local pitch_deg, yaw_bf_deg = message_attitude(message)
  mount:set_attitude_euler(SETTINGS.MOUNT_INSTANCE, 0, pitch_deg, yaw_bf_deg)
  if VSH_DEBUG:get() > 1 then
    gcs:send_text(MAV_SEVERITY.DEBUG, string.format("VSH: pitch %.1f yaw %.1f", pitch_deg, yaw_bf_deg))
  end
end

local function is_header(segment)
  return #segment >= 3 and segment[1] == PROTOCOL.header[1] and segment[2] == PROTOCOL.header[2]
    and FEEDBACK[segment[3]] ~= nil
end

-- true when the gathered bytes are a whole message whose CRC is right
function codec.message_ok(message)
  local layout = FEEDBACK[message[3]]
  if #message < layout.crc_off + 2 then
    return false
  end
  local sent = message[layout.crc_off + 1] | (message[layout.crc_off + 2] << 8)
  return codec.crc16(message, layout.crc_off) == sent
end

-- check and hand on the message of the segments gathered so far; false if it is not whole
local function finish_message(now)
  if not codec.message_ok(feedback.segments) then
    return false
  end
  handle_message(feedback.segments)
  feedback.last_message_ms = now
  feedback.seen = true
  if feedback.lost then
    feedback.lost = false
    state.sent_pitch, state.sent_yaw = nil, nil  -- the gimbal may have restarted: the target again
    gcs:send_text(MAV_SEVERITY.INFO, "VSH: gimbal feedback resumed")
  end
  return true
end

local function start_message()
  feedback.segments = {}
  feedback.count = 0
end

local function drop_message(crc_error)
  if crc_error then
    counts.crc = counts.crc + 1
    counts.unreported_crc = counts.unreported_crc + 1
  else
    counts.cut = counts.cut + 1
    counts.unreported_cut = counts.unreported_cut + 1
  end
  start_message()
end

local function append(segment)
  local bytes = feedback.segments
  for i = 1, #segment do
    bytes[#bytes + 1] = segment[i]
  end
end

-- a header while a message is open: the open one lost a segment, unless this is its last
-- segment and the CRC says so; true when it was
local function header_completes(segment, now)
  if feedback.count ~= PROTOCOL.segments - 1 then
    return false
  end
  local saved = #feedback.segments
  append(segment)
  if finish_message(now) then
    return true
  end
  for i = #feedback.segments, saved + 1, -1 do
    feedback.segments[i] = nil
  end
  return false
end

-- one 8-byte segment of the feedback's CAN ID: four of them make a message
local function feedback_segment(segment, now)
  if feedback.count > 0 and now - feedback.last_segment_ms > INTERVAL_MS.SEGMENT_TIMEOUT then
    drop_message(false)
  end
  if is_header(segment) and feedback.count > 0 then
    if header_completes(segment, now) then
      start_message()
      feedback.last_segment_ms = now
      return
    end
    drop_message(false)
  end
  if feedback.count == 0 and not is_header(segment) then
    if feedback.seen then
      drop_message(false)                 -- a segment whose message lost its header
    end                                   -- (before the first message: started mid-way)
    return
  end
  append(segment)
  feedback.count = feedback.count + 1
  feedback.last_segment_ms = now
  if feedback.count == PROTOCOL.segments then
    if finish_message(now) then
      start_message()
    else
      drop_message(true)
    end
  end
end

local function read_incoming_frames(now)
  for _ = 1, SETTINGS.CAN_BUFFER_LEN do
    local frame = driver:read_frame()
    if not frame then
      return
    end
    counts.read = counts.read + 1
    if frame:id() == FRAME_ID.FEEDBACK then
      local segment = {}
      for i = 0, frame:dlc() - 1 do
        segment[i + 1] = frame:data(i)
      end
      feedback_segment(segment, now)
    else
      counts.ignored = counts.ignored + 1
    end
  end
end

-- tell the GCS when the feedback stops or arrives damaged (at most every 5 s)
local function report_problems(now)
  if not feedback.lost and now - feedback.last_message_ms > INTERVAL_MS.FEEDBACK_TIMEOUT then
    feedback.lost = true
    gcs:send_text(MAV_SEVERITY.WARNING, "VSH: no feedback from the gimbal")
  end
  if counts.unreported_crc + counts.unreported_cut == 0 then
    return
  end
  if state.reported_once and now - state.last_report_ms < INTERVAL_MS.REPORT then
    return
  end
  gcs:send_text(MAV_SEVERITY.WARNING, string.format("VSH: feedback dropped: %d CRC, %d cut",
    counts.unreported_crc, counts.unreported_cut))
  counts.unreported_crc = 0
  counts.unreported_cut = 0
  state.last_report_ms = now
  state.reported_once = true
end

-- the UAV's attitude frame (degrees; yaw -180 .. 180)
function codec.attitude_frame(pitch_deg, roll_deg, yaw_deg)
  local fields = STATUS.attitude.fields
  local data = {0, 0, 0, 0, 0, 0, 0, 0}
  codec.put(data, fields.pitch_deg, pitch_deg)
  codec.put(data, fields.roll_deg, roll_deg)
  codec.put(data, fields.yaw_deg, yaw_deg)
  return data
end

-- the UAV's GPS frame of a Location (degrees * 1e7 as integers: the frame's own unit)
function codec.gps_frame(loc)
  local fields = STATUS.gps.fields
  local data = {0, 0, 0, 0, 0, 0, 0, 0}
  codec.put_raw(data, fields.latitude_deg, loc:lat())
  codec.put_raw(data, fields.longitude_deg, loc:lng())
  return data
end

function codec.altitude_frame(altitude_m)
  local data = {0, 0, 0, 0, 0, 0, 0, 0}
  codec.put(data, STATUS.altitude.fields.altitude_m, altitude_m)
  return data
end

-- the UAV status the gimbal needs for north-referenced angles, on a fixed schedule
local function send_uav_status(now)
  if timer_due(timers.attitude, now) then
    local yaw_deg = wrap_180(math.deg(ahrs:get_yaw_rad()))
    send_frame(FRAME_ID.ATTITUDE, codec.attitude_frame(math.deg(ahrs:get_pitch_rad()), math.deg(ahrs:get_roll_rad()), yaw_deg))
  end
  if not timer_due(timers.position, now) then
    return
  end
  local gps_instance = gps:primary_sensor()
  if gps:status(gps_instance) >= gps.GPS_OK_FIX_3D then
    send_frame(FRAME_ID.GPS, codec.gps_frame(gps:location(gps_instance)))
  end
  send_frame(FRAME_ID.ALTITUDE, codec.altitude_frame(-ahrs:get_relative_position_D_home()))
end

-- rates: gimbal_control every 50 ms while they last, one with speeds 0 when they stop
local function stop_rates()
  if state.rates_moving then
    state.rates_moving = false
    send_command("gimbal_control", {pan_speed_dps = 0, tilt_speed_dps = 0})
  end
end

local function send_rates(pitch_degs, yaw_degs)
  local fields = COMMANDS.gimbal_control.fields
  if codec.raw_value(fields.pan_speed_dps, yaw_degs) == 0 and codec.raw_value(fields.tilt_speed_dps, pitch_degs) == 0 then
    stop_rates()
    return
  end
  state.rates_moving = true
  state.sent_pitch, state.sent_yaw = nil, nil  -- the gimbal leaves any angle it held
  send_command("gimbal_control", {pan_speed_dps = yaw_degs, tilt_speed_dps = pitch_degs})
end

-- angles: specified_angle for pitch and for yaw, each when it changes
local function send_angles(pitch_deg, yaw_deg, yaw_is_earth_frame)
  local angle = COMMANDS.specified_angle
  local axis = angle.fields.axis.labels
  local frames = angle.fields.coordinate_system.labels
  local pitch_raw = codec.raw_value(angle.fields.pitch_deg, pitch_deg)
  if pitch_raw ~= state.sent_pitch then
    state.sent_pitch = pitch_raw
    send_command("specified_angle", {axis = axis.pitch, pitch_deg = pitch_deg})
  end
  local frame = yaw_is_earth_frame and frames.geodetic or frames.airframe
  local yaw_raw = codec.raw_value(angle.fields.yaw_deg, wrap_360(yaw_deg))
  if yaw_raw ~= state.sent_yaw or frame ~= state.sent_yaw_frame then
    state.sent_yaw = yaw_raw
    state.sent_yaw_frame = frame
    send_command("specified_angle", {axis = axis.yaw, yaw_deg = wrap_360(yaw_deg), coordinate_system = frame})
  end
end

-- the angles to `target` from `here` (both Locations), as ArduPilot's mount library
-- computes them: heights above home, pitch up from level, yaw 0 .. 360 from north
local function angles_to(here, target)
  local target_loc = target:copy()
  local here_loc = here:copy()
  if not target_loc:change_alt_frame(1) or not here_loc:change_alt_frame(1) then
    return nil
  end
  local ne = here_loc:get_distance_NE(target_loc)
  local up_m = (target_loc:alt() - here_loc:alt()) * 0.01
  local pitch_deg = math.deg(math.atan(up_m, math.sqrt(ne:x() * ne:x() + ne:y() * ne:y())))
  return pitch_deg, wrap_360(math.deg(math.atan(ne:y(), ne:x())))
end

-- a location target: the angles to it, at most every 2 s and when they moved 1 deg
local function point_at(target, now)
  local here = ahrs:get_location()
  if not here then
    return
  end
  local pitch_deg, yaw_deg = angles_to(here, target)
  if not pitch_deg then
    return
  end
  if state.location_pitch_deg and now - state.last_location_ms < INTERVAL_MS.LOCATION then
    return
  end
  if state.location_pitch_deg and math.abs(pitch_deg - state.location_pitch_deg) < SETTINGS.LOCATION_STEP_DEG
      and math.abs(wrap_180(yaw_deg - state.location_yaw_deg)) < SETTINGS.LOCATION_STEP_DEG then
    return
  end
  state.location_pitch_deg, state.location_yaw_deg = pitch_deg, yaw_deg
  state.last_location_ms = now
  send_angles(pitch_deg, yaw_deg, true)
end

local function update_mount_target(now)
  if not timer_due(timers.target, now) then
    return
  end
  if camera_state.track_type ~= 0 then
    -- the gimbal's tracker steers while the camera tracks: targets wait until it stops
    stop_rates()
    return
  end
  local target = mount:get_location_target(SETTINGS.MOUNT_INSTANCE)
  if target then
    stop_rates()
    point_at(target, now)
    return
  end
  state.location_pitch_deg, state.location_yaw_deg = nil, nil
  local roll_deg, pitch_deg, yaw_deg, yaw_is_ef = mount:get_angle_target(SETTINGS.MOUNT_INSTANCE)
  if roll_deg and pitch_deg and yaw_deg then
    stop_rates()
    send_angles(pitch_deg, yaw_deg, yaw_is_ef)
    return
  end
  local roll_degs, pitch_degs, yaw_degs = mount:get_rate_target(SETTINGS.MOUNT_INSTANCE)
  if roll_degs and pitch_degs and yaw_degs then
    send_rates(pitch_degs, yaw_degs)
    return
  end
  stop_rates()
end

-- tracking box: a point gets a square of TRACK_POINT_SIZE, a rectangle its own size
local function tracking_values(track_type, x1, y1, x2, y2)
  local size = PROTOCOL.image_size - 1
  if track_type == 1 then
    return {x = x1 * size, y = y1 * size, width = SETTINGS.TRACK_POINT_SIZE, height = SETTINGS.TRACK_POINT_SIZE}
  end
  return {x = (x1 + x2) / 2 * size, y = (y1 + y2) / 2 * size,
    width = math.abs(x2 - x1) * size, height = math.abs(y2 - y1) * size}
end

-- a zoom request in percent of the zoom range (0 = 1x) as the zoom ratio to ask for
local function zoom_ratio(percent)
  percent = math.max(0, math.min(100, percent))
  return 1 + (VSH_ZOOM_MAX:get() - 1) * percent / 100
end

-- a rate of the camera library (-1, 0, 1) as one of three actions
local function rate_action(value, labels, up, down)
  if value > 0 then
    return labels[up]
  elseif value < 0 then
    return labels[down]
  end
  return labels.stop
end

local function update_zoom(state_ud)
  camera_state.zoom_type, camera_state.zoom_value = state_ud:zoom_type(), state_ud:zoom_value()
  local labels = COMMANDS.zoom.fields.action.labels
  if camera_state.zoom_type == 1 then       -- rate: zoom out = -1, hold = 0, zoom in = 1
    send_command("zoom", {action = rate_action(camera_state.zoom_value, labels, "zoom_in", "zoom_out")})
  elseif camera_state.zoom_type == 2 then   -- percentage of the zoom range, 0 = 1x
    local axis = COMMANDS.specified_angle.fields.axis.labels
    send_command("specified_angle", {axis = axis.zoom, zoom = zoom_ratio(camera_state.zoom_value)})
  end
end

local function update_focus(state_ud)
  camera_state.focus_type, camera_state.focus_value = state_ud:focus_type(), state_ud:focus_value()
  local labels = COMMANDS.focus.fields.action.labels
  if camera_state.focus_type == 1 then      -- rate: focus in = -1, hold = 0, focus out = 1
    send_command("focus", {action = rate_action(camera_state.focus_value, labels, "focus_plus", "focus_minus")})
  elseif camera_state.focus_type == 4 then
    send_command("focus", {action = labels.auto_focus})
  elseif VSH_DEBUG:get() > 0 then
    gcs:send_text(MAV_SEVERITY.INFO, "VSH: focus to a percentage not supported")
  end
end

local function update_tracking(track_type, track)
  camera_state.track_type, camera_state.track = track_type, track
  if track_type == 0 then
    send_command("tracking_stop", {})
    state.sent_pitch, state.sent_yaw, state.location_pitch_deg = nil, nil, nil  -- the target again
  else
    send_command("tracking", tracking_values(track_type, track[1], track[2], track[3], track[4]))
  end
end

-- camera library: what changed in camera:get_state becomes the gimbal's camera commands
local function update_camera()
  local cam = camera:get_state(SETTINGS.CAMERA_INSTANCE)
  if not cam then
    return
  end
  local p1, p2 = cam:tracking_p1(), cam:tracking_p2()
  local track = {p1:x(), p1:y(), p2:x(), p2:y()}
  if not camera_state.seen then
    -- the state at start-up asks for nothing
    camera_state.seen = true
    camera_state.pic_count, camera_state.recording = cam:take_pic_incr(), cam:recording_video()
    camera_state.zoom_type, camera_state.zoom_value = cam:zoom_type(), cam:zoom_value()
    camera_state.focus_type, camera_state.focus_value = cam:focus_type(), cam:focus_value()
    camera_state.track_type, camera_state.track = cam:tracking_type(), track
    return
  end
  if cam:take_pic_incr() ~= camera_state.pic_count then
    camera_state.pic_count = cam:take_pic_incr()
    send_command("snapshot", {mode = COMMANDS.snapshot.fields.mode.labels.single})
  end
  if cam:recording_video() ~= camera_state.recording then
    camera_state.recording = cam:recording_video()
    local labels = COMMANDS.recording.fields.action.labels
    send_command("recording", {action = camera_state.recording and labels.start or labels.stop})
  end
  if cam:zoom_type() ~= camera_state.zoom_type or cam:zoom_value() ~= camera_state.zoom_value then
    update_zoom(cam)
  end
  if cam:focus_type() ~= camera_state.focus_type or cam:focus_value() ~= camera_state.focus_value then
    update_focus(cam)
  end
  local old = camera_state.track
  local moved = track[1] ~= old[1] or track[2] ~= old[2] or track[3] ~= old[3] or track[4] ~= old[4]
  if cam:tracking_type() ~= camera_state.track_type or (cam:tracking_type() ~= 0 and moved) then
    update_tracking(cam:tracking_type(), track)
  end
end

local function report_debug(now)
  if VSH_DEBUG:get() < 1 or not timer_due(timers.debug, now) then
    return
  end
  gcs:send_text(MAV_SEVERITY.DEBUG, string.format("VSH: rx %d tx %d ok %d crc %d cut %d",
    counts.read, counts.sent, counts.ok, counts.crc, counts.cut))
end

local function update()
  if not state.initialised then
    init()
    if not state.initialised then
      return update, INTERVAL_MS.INIT
    end
  end
  local now = millis()
  read_incoming_frames(now)
  report_problems(now)
  send_uav_status(now)
  update_mount_target(now)
  update_camera()
  report_debug(now)
  return update, INTERVAL_MS.UPDATE
end

return update()
