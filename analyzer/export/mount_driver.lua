-- The driver body; the tables above it are generated from the protocol tables.

-- parameters
assert(param:add_table(PARAM_TABLE_KEY, PARAM_TABLE_PREFIX, 3), "VSH: could not add param table")
assert(param:add_param(PARAM_TABLE_KEY, 1, "CAN_DRV", 1), "VSH: could not add VSH_CAN_DRV")
assert(param:add_param(PARAM_TABLE_KEY, 2, "DEBUG", 0), "VSH: could not add VSH_DEBUG")
assert(param:add_param(PARAM_TABLE_KEY, 3, "ZOOM_MAX", DEFAULT_ZOOM_MAX), "VSH: could not add VSH_ZOOM_MAX")

--[[
  // @Param: VSH_CAN_DRV
  // @DisplayName: Gimbal CAN driver
  // @Description: Scripting CAN driver the gimbal is on: 1 is the driver whose CAN_Dx_PROTOCOL is 10 (Scripting), 2 the one whose CAN_Dx_PROTOCOL is 12 (Scripting2)
  // @Values: 1:First scripting CAN driver,2:Second scripting CAN driver
  // @User: Standard
--]]
local VSH_CAN_DRV = Parameter("VSH_CAN_DRV")

--[[
  // @Param: VSH_DEBUG
  // @DisplayName: Gimbal driver debug
  // @Description: Debug messages to the GCS: 1 counters every 5 s, 2 the gimbal's attitude too
  // @Values: 0:Disabled,1:Enabled,2:Enabled with attitude reporting
  // @User: Advanced
--]]
local VSH_DEBUG = Parameter("VSH_DEBUG")

--[[
  // @Param: VSH_ZOOM_MAX
  // @DisplayName: Gimbal camera zoom maximum
  // @Description: Zoom ratio of a 100% zoom request (a 0% request is 1x)
  // @Range: 1 35
  // @User: Standard
--]]
local VSH_ZOOM_MAX = Parameter("VSH_ZOOM_MAX")

local MNT1_TYPE = Parameter("MNT1_TYPE")    -- should be 9:Scripting

-- timing
local INIT_INTERVAL_MS = 3000           -- retry the set-up at this interval
local UPDATE_INTERVAL_MS = 10           -- run at 100 Hz
local TARGET_INTERVAL_MS = 50           -- gimbal_control every 50 ms, as the protocol document recommends
local ATTITUDE_INTERVAL_MS = 100        -- UAV attitude to the gimbal at 10 Hz
local POSITION_INTERVAL_MS = 200        -- UAV GPS and altitude to the gimbal at 5 Hz
local LOCATION_INTERVAL_MS = 2000       -- angles to a location target at most this often ...
local LOCATION_STEP_DEG = 1.0           -- ... and when they moved at least this much
local FEEDBACK_TIMEOUT_MS = 2000        -- no feedback this long (4 messages): the gimbal is silent
local SEGMENT_TIMEOUT_MS = 200          -- a feedback message's segments come within this
local REPORT_INTERVAL_MS = 5000         -- at most one problem report to the GCS this often
local WRITE_TIMEOUT_US = 10000          -- write_frame waits at most 10 ms (its timeout is in microseconds)
local CAN_BUFFER_LEN = 25               -- frames buffered between updates (1 to 25)
local MAX_FRAMES_PER_UPDATE = CAN_BUFFER_LEN

local MOUNT_INSTANCE = 0                -- the first mount (MNT1)
local CAMERA_INSTANCE = 0               -- the first camera (CAM1)
local MAV_SEVERITY = {EMERGENCY=0, ALERT=1, CRITICAL=2, ERROR=3, WARNING=4, NOTICE=5, INFO=6, DEBUG=7}

-- ArduPilot marks an extended (29-bit) CAN ID with bit 31 of a CANFrame's id
local EXTENDED_FLAG = uint32_t(1) << 31
local CONTROL_FRAME_ID = uint32_t(CONTROL_ID) | EXTENDED_FLAG
local FEEDBACK_FRAME_ID = uint32_t(FEEDBACK_ID) | EXTENDED_FLAG
local GPS_FRAME_ID = uint32_t(STATUS.gps.id) | EXTENDED_FLAG
local ALTITUDE_FRAME_ID = uint32_t(STATUS.altitude.id) | EXTENDED_FLAG
local ATTITUDE_FRAME_ID = uint32_t(STATUS.attitude.id) | EXTENDED_FLAG

-- state
local driver = nil                      -- the scripting CAN buffer
local initialised = false
local last_target_ms = uint32_t(0)
local last_attitude_ms = uint32_t(0)
local last_position_ms = uint32_t(0)
local rates_moving = false              -- gimbal_control with a speed was the last rate sent
local sent_pitch = nil                  -- raw values of the last specified_angle per axis
local sent_yaw = nil
local sent_yaw_frame = nil
local location_pitch_deg = nil          -- angles last sent for a location target
local location_yaw_deg = nil
local last_location_ms = uint32_t(0)
local camera_seen = false
local cam_pic_count = 0
local cam_recording = false
local cam_zoom_type = 0
local cam_zoom_value = 0
local cam_focus_type = 0
local cam_focus_value = 0
local cam_track_type = 0
local cam_track = {0, 0, 0, 0}

-- feedback reassembly
local segments = {}                     -- bytes of the message being reassembled
local segment_count = 0
local last_segment_ms = uint32_t(0)
local last_feedback_ms = uint32_t(0)
local feedback_seen = false
local feedback_lost = false
local started_ms = uint32_t(0)

-- counters
local frames_read = 0
local frames_sent = 0
local write_fails = 0
local frames_ignored = 0
local messages_ok = 0
local crc_errors = 0
local incomplete = 0
local unreported_crc = 0
local unreported_incomplete = 0
local last_report_ms = uint32_t(0)
local reported_once = false
local last_debug_ms = uint32_t(0)

-- milliseconds from `since` to `now` (both millis() values; safe across the 49-day wrap)
local function elapsed_ms(now, since)
  return (now - since):toint()
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

-- a physical value as the integer a field carries: scaled, rounded and kept inside the
-- document's range (a value outside it is never sent)
local function raw_value(field, value)
  local raw = math.floor(value * field.div / field.mul + 0.5)
  if raw ~= raw then                      -- not a number: send the field's zero point
    raw = 0
  end
  if raw < field.min then
    raw = field.min
  elseif raw > field.max then
    raw = field.max
  end
  return raw
end

-- write a raw integer into a byte table (1-based) at the field's offset, little-endian,
-- kept inside the document's range
local function put_raw(data, field, raw)
  if raw < field.min then
    raw = field.min
  elseif raw > field.max then
    raw = field.max
  end
  for i = 0, field.size - 1 do
    data[field.off + 1 + i] = (raw >> (8 * i)) & 0xFF
  end
end

local function put(data, field, value)
  put_raw(data, field, raw_value(field, value))
end

-- read a field of a byte table (1-based) as its physical value
local function get(data, field)
  local raw = 0
  for i = field.size - 1, 0, -1 do
    raw = (raw << 8) | data[field.off + 1 + i]
  end
  if field.signed and raw >= (1 << (8 * field.size - 1)) then
    raw = raw - (1 << (8 * field.size))
  end
  return raw * field.mul / field.div
end

local function crc16(data, count)
  local crc = CRC_INIT
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
  if driver:write_frame(frame, WRITE_TIMEOUT_US) then
    frames_sent = frames_sent + 1
  else
    write_fails = write_fails + 1
  end
end

-- a command's 8 CAN bytes: S_ID, CMD, then its fields (labels are given as their codes)
local function send_command(name, values)
  local command = COMMANDS[name]
  local data = {command.s_id, command.cmd, 0, 0, 0, 0, 0, 0}
  for field_name, value in pairs(values) do
    local field = command.fields[field_name]
    if field.labels then
      put_raw(data, field, value)
    else
      put(data, field, value)
    end
  end
  send_frame(CONTROL_FRAME_ID, data)
end

-- set-up: the scripting CAN driver chosen by VSH_CAN_DRV
local function init()
  if MNT1_TYPE:get() ~= 9 then
    gcs:send_text(MAV_SEVERITY.CRITICAL, "VSH: set MNT1_TYPE=9")
    return
  end
  local which = VSH_CAN_DRV:get()
  if which == 1 then
    driver = CAN:get_device(CAN_BUFFER_LEN)
  elseif which == 2 then
    driver = CAN:get_device2(CAN_BUFFER_LEN)
  else
    gcs:send_text(MAV_SEVERITY.CRITICAL, "VSH: set VSH_CAN_DRV to 1 or 2")
    return
  end
  if not driver then
    gcs:send_text(MAV_SEVERITY.CRITICAL, string.format("VSH: no scripting CAN driver %d", which))
    return
  end
  initialised = true
  started_ms = millis()
  gcs:send_text(MAV_SEVERITY.INFO, "VSH: mount driver started")
end

-- a good feedback message: report the attitude to the mount library
local function handle_message(message)
  messages_ok = messages_ok + 1
  local layout = FEEDBACK[message[3]]
  if layout.name ~= "attitude" then
    return
  end
  local pitch_deg = get(message, layout.fields.pitch_deg)
  local yaw_bf_deg = wrap_180(get(message, layout.fields.motor_yaw_deg))
  mount:set_attitude_euler(MOUNT_INSTANCE, 0, pitch_deg, yaw_bf_deg)
  if VSH_DEBUG:get() > 1 then
    gcs:send_text(MAV_SEVERITY.DEBUG, string.format("VSH: pitch %.1f yaw %.1f", pitch_deg, yaw_bf_deg))
  end
end

local function is_header(segment)
  return #segment >= 3 and segment[1] == HEADER[1] and segment[2] == HEADER[2] and FEEDBACK[segment[3]] ~= nil
end

-- check and hand on the message of the segments gathered so far; false if it is not whole
local function finish_message(now)
  local layout = FEEDBACK[segments[3]]
  local crc = crc16(segments, layout.crc_off)
  local sent = segments[layout.crc_off + 1] | (segments[layout.crc_off + 2] << 8)
  if crc ~= sent then
    return false
  end
  handle_message(segments)
  last_feedback_ms = now
  feedback_seen = true
  if feedback_lost then
    feedback_lost = false
    sent_pitch, sent_yaw = nil, nil       -- the gimbal may have restarted: send the target again
    gcs:send_text(MAV_SEVERITY.INFO, "VSH: gimbal feedback resumed")
  end
  return true
end

local function drop_message(crc_error)
  if crc_error then
    crc_errors = crc_errors + 1
    unreported_crc = unreported_crc + 1
  else
    incomplete = incomplete + 1
    unreported_incomplete = unreported_incomplete + 1
  end
  segments = {}
  segment_count = 0
end

-- one 8-byte segment of CAN ID 0x030F0001: four of them make a message
local function feedback_segment(segment, now)
  if segment_count > 0 and elapsed_ms(now, last_segment_ms) > SEGMENT_TIMEOUT_MS then
    drop_message(false)
  end
  if is_header(segment) and segment_count > 0 then
    -- a header while a message is open: the open one lost a segment, unless this is its
    -- last segment and the CRC says so
    local whole = false
    if segment_count == FEEDBACK_SEGMENTS - 1 then
      local saved = #segments
      for i = 1, #segment do
        segments[saved + i] = segment[i]
      end
      whole = finish_message(now)
      if not whole then
        for i = #segments, saved + 1, -1 do
          segments[i] = nil
        end
      end
    end
    if whole then
      segments = {}
      segment_count = 0
      last_segment_ms = now
      return
    end
    drop_message(false)
  end
  if segment_count == 0 and not is_header(segment) then
    if feedback_seen then
      drop_message(false)                 -- a segment whose message lost its header
    end                                   -- (before the first message: started mid-way)
    return
  end
  for i = 1, #segment do
    segments[#segments + 1] = segment[i]
  end
  segment_count = segment_count + 1
  last_segment_ms = now
  if segment_count == FEEDBACK_SEGMENTS then
    if finish_message(now) then
      segments = {}
      segment_count = 0
    else
      drop_message(true)
    end
  end
end

local function read_incoming_frames(now)
  for _ = 1, MAX_FRAMES_PER_UPDATE do
    local frame = driver:read_frame()
    if not frame then
      return
    end
    frames_read = frames_read + 1
    if frame:id() == FEEDBACK_FRAME_ID then
      local segment = {}
      for i = 0, frame:dlc() - 1 do
        segment[i + 1] = frame:data(i)
      end
      feedback_segment(segment, now)
    else
      frames_ignored = frames_ignored + 1
    end
  end
end

-- tell the GCS when the feedback stops or arrives damaged (at most every 5 s)
local function report_problems(now)
  if not feedback_lost and elapsed_ms(now, feedback_seen and last_feedback_ms or started_ms) > FEEDBACK_TIMEOUT_MS then
    feedback_lost = true
    gcs:send_text(MAV_SEVERITY.WARNING, "VSH: no feedback from the gimbal")
  end
  if unreported_crc + unreported_incomplete == 0 then
    return
  end
  if reported_once and elapsed_ms(now, last_report_ms) < REPORT_INTERVAL_MS then
    return
  end
  gcs:send_text(MAV_SEVERITY.WARNING, string.format("VSH: feedback dropped: %d CRC, %d cut",
    unreported_crc, unreported_incomplete))
  unreported_crc = 0
  unreported_incomplete = 0
  last_report_ms = now
  reported_once = true
end

-- the UAV status the gimbal needs for north-referenced angles
local function send_uav_status(now)
  if elapsed_ms(now, last_attitude_ms) >= ATTITUDE_INTERVAL_MS then
    last_attitude_ms = now
    local fields = STATUS.attitude.fields
    local data = {0, 0, 0, 0, 0, 0, 0, 0}
    put(data, fields.pitch_deg, math.deg(ahrs:get_pitch()))
    put(data, fields.roll_deg, math.deg(ahrs:get_roll()))
    put(data, fields.yaw_deg, wrap_180(math.deg(ahrs:get_yaw())))
    send_frame(ATTITUDE_FRAME_ID, data)
  end
  if elapsed_ms(now, last_position_ms) < POSITION_INTERVAL_MS then
    return
  end
  last_position_ms = now
  local gps_instance = gps:primary_sensor()
  if gps:status(gps_instance) >= gps.GPS_OK_FIX_3D then
    local loc = gps:location(gps_instance)
    local fields = STATUS.gps.fields
    local data = {0, 0, 0, 0, 0, 0, 0, 0}
    -- Location keeps degrees * 1e7 as integers, the very unit of the frame
    put_raw(data, fields.latitude_deg, loc:lat())
    put_raw(data, fields.longitude_deg, loc:lng())
    send_frame(GPS_FRAME_ID, data)
  end
  local data = {0, 0, 0, 0, 0, 0, 0, 0}
  put(data, STATUS.altitude.fields.altitude_m, -ahrs:get_relative_position_D_home())
  send_frame(ALTITUDE_FRAME_ID, data)
end

-- rates: gimbal_control every 50 ms while they last, one with speeds 0 when they stop
local function stop_rates()
  if rates_moving then
    rates_moving = false
    send_command("gimbal_control", {pan_speed_dps = 0, tilt_speed_dps = 0})
  end
end

local function send_rates(pitch_degs, yaw_degs)
  local fields = COMMANDS.gimbal_control.fields
  if raw_value(fields.pan_speed_dps, yaw_degs) == 0 and raw_value(fields.tilt_speed_dps, pitch_degs) == 0 then
    stop_rates()
    return
  end
  rates_moving = true
  sent_pitch, sent_yaw = nil, nil         -- the gimbal leaves any angle it held
  send_command("gimbal_control", {pan_speed_dps = yaw_degs, tilt_speed_dps = pitch_degs})
end

-- angles: specified_angle for pitch and for yaw, each when it changes
local function send_angles(pitch_deg, yaw_deg, yaw_is_earth_frame)
  local angle = COMMANDS.specified_angle
  local axis = angle.fields.axis.labels
  local frames = angle.fields.coordinate_system.labels
  local pitch_raw = raw_value(angle.fields.pitch_deg, pitch_deg)
  if pitch_raw ~= sent_pitch then
    sent_pitch = pitch_raw
    send_command("specified_angle", {axis = axis.pitch, pitch_deg = pitch_deg})
  end
  local frame = yaw_is_earth_frame and frames.geodetic or frames.airframe
  local yaw_raw = raw_value(angle.fields.yaw_deg, wrap_360(yaw_deg))
  if yaw_raw ~= sent_yaw or frame ~= sent_yaw_frame then
    sent_yaw = yaw_raw
    sent_yaw_frame = frame
    send_command("specified_angle", {axis = axis.yaw, yaw_deg = wrap_360(yaw_deg), coordinate_system = frame})
  end
end

-- a location target: the angles to it from the aircraft, as ArduPilot's mount library
-- computes them (heights above home, yaw from north)
local function point_at(target, now)
  local here = ahrs:get_location()
  if not here then
    return
  end
  local target_loc = target:copy()
  local here_loc = here:copy()
  if not target_loc:change_alt_frame(1) or not here_loc:change_alt_frame(1) then
    return
  end
  local ne = here_loc:get_distance_NE(target_loc)
  local up_m = (target_loc:alt() - here_loc:alt()) * 0.01
  local pitch_deg = math.deg(math.atan(up_m, math.sqrt(ne:x() * ne:x() + ne:y() * ne:y())))
  local yaw_deg = wrap_360(math.deg(math.atan(ne:y(), ne:x())))
  if location_pitch_deg and elapsed_ms(now, last_location_ms) < LOCATION_INTERVAL_MS then
    return
  end
  if location_pitch_deg and math.abs(pitch_deg - location_pitch_deg) < LOCATION_STEP_DEG
      and math.abs(wrap_180(yaw_deg - location_yaw_deg)) < LOCATION_STEP_DEG then
    return
  end
  location_pitch_deg, location_yaw_deg = pitch_deg, yaw_deg
  last_location_ms = now
  send_angles(pitch_deg, yaw_deg, true)
end

local function update_mount_target(now)
  if elapsed_ms(now, last_target_ms) < TARGET_INTERVAL_MS then
    return
  end
  last_target_ms = now
  if cam_track_type ~= 0 then
    -- the gimbal's tracker steers while the camera tracks: targets wait until it stops
    stop_rates()
    return
  end
  local target = mount:get_location_target(MOUNT_INSTANCE)
  if target then
    stop_rates()
    point_at(target, now)
    return
  end
  location_pitch_deg, location_yaw_deg = nil, nil
  local roll_deg, pitch_deg, yaw_deg, yaw_is_ef = mount:get_angle_target(MOUNT_INSTANCE)
  if roll_deg and pitch_deg and yaw_deg then
    stop_rates()
    send_angles(pitch_deg, yaw_deg, yaw_is_ef)
    return
  end
  local roll_degs, pitch_degs, yaw_degs = mount:get_rate_target(MOUNT_INSTANCE)
  if roll_degs and pitch_degs and yaw_degs then
    send_rates(pitch_degs, yaw_degs)
    return
  end
  stop_rates()
end

-- tracking box: a point gets a square of TRACK_POINT_SIZE, a rectangle its own size
local function send_tracking(track_type, x1, y1, x2, y2)
  local size = IMAGE_SIZE - 1
  if track_type == 1 then
    send_command("tracking", {x = x1 * size, y = y1 * size, width = TRACK_POINT_SIZE, height = TRACK_POINT_SIZE})
  else
    send_command("tracking", {x = (x1 + x2) / 2 * size, y = (y1 + y2) / 2 * size,
      width = math.abs(x2 - x1) * size, height = math.abs(y2 - y1) * size})
  end
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

-- camera library: what changed in camera:get_state becomes the gimbal's camera commands
local function update_camera()
  local state = camera:get_state(CAMERA_INSTANCE)
  if not state then
    return
  end
  local p1, p2 = state:tracking_p1(), state:tracking_p2()
  local track = {p1:x(), p1:y(), p2:x(), p2:y()}
  if not camera_seen then
    -- the state at start-up asks for nothing
    camera_seen = true
    cam_pic_count = state:take_pic_incr()
    cam_recording = state:recording_video()
    cam_zoom_type, cam_zoom_value = state:zoom_type(), state:zoom_value()
    cam_focus_type, cam_focus_value = state:focus_type(), state:focus_value()
    cam_track_type, cam_track = state:tracking_type(), track
    return
  end
  local labels = {}
  if state:take_pic_incr() ~= cam_pic_count then
    cam_pic_count = state:take_pic_incr()
    send_command("snapshot", {mode = COMMANDS.snapshot.fields.mode.labels.single})
  end
  if state:recording_video() ~= cam_recording then
    cam_recording = state:recording_video()
    labels = COMMANDS.recording.fields.action.labels
    send_command("recording", {action = cam_recording and labels.start or labels.stop})
  end
  if state:zoom_type() ~= cam_zoom_type or state:zoom_value() ~= cam_zoom_value then
    cam_zoom_type, cam_zoom_value = state:zoom_type(), state:zoom_value()
    labels = COMMANDS.zoom.fields.action.labels
    if cam_zoom_type == 1 then            -- rate: zoom out = -1, hold = 0, zoom in = 1
      send_command("zoom", {action = rate_action(cam_zoom_value, labels, "zoom_in", "zoom_out")})
    elseif cam_zoom_type == 2 then        -- percentage of the zoom range, 0 = 1x
      local percent = math.max(0, math.min(100, cam_zoom_value))
      local ratio = 1 + (VSH_ZOOM_MAX:get() - 1) * percent / 100
      send_command("specified_angle", {axis = COMMANDS.specified_angle.fields.axis.labels.zoom, zoom = ratio})
    end
  end
  if state:focus_type() ~= cam_focus_type or state:focus_value() ~= cam_focus_value then
    cam_focus_type, cam_focus_value = state:focus_type(), state:focus_value()
    labels = COMMANDS.focus.fields.action.labels
    if cam_focus_type == 1 then           -- rate: focus in = -1, hold = 0, focus out = 1
      send_command("focus", {action = rate_action(cam_focus_value, labels, "focus_plus", "focus_minus")})
    elseif cam_focus_type == 4 then
      send_command("focus", {action = labels.auto_focus})
    elseif VSH_DEBUG:get() > 0 then
      gcs:send_text(MAV_SEVERITY.INFO, "VSH: focus to a percentage not supported")
    end
  end
  local moved = track[1] ~= cam_track[1] or track[2] ~= cam_track[2] or track[3] ~= cam_track[3] or track[4] ~= cam_track[4]
  if state:tracking_type() ~= cam_track_type or (state:tracking_type() ~= 0 and moved) then
    cam_track_type, cam_track = state:tracking_type(), track
    if cam_track_type == 0 then
      send_command("tracking_stop", {})
      sent_pitch, sent_yaw, location_pitch_deg = nil, nil, nil  -- the target again
    else
      send_tracking(cam_track_type, track[1], track[2], track[3], track[4])
    end
  end
end

local function report_debug(now)
  if VSH_DEBUG:get() < 1 or elapsed_ms(now, last_debug_ms) < REPORT_INTERVAL_MS then
    return
  end
  last_debug_ms = now
  gcs:send_text(MAV_SEVERITY.DEBUG, string.format("VSH: rx %d tx %d ok %d crc %d cut %d",
    frames_read, frames_sent, messages_ok, crc_errors, incomplete))
end

local function update()
  if not initialised then
    init()
    if not initialised then
      return update, INIT_INTERVAL_MS
    end
  end
  local now = millis()
  read_incoming_frames(now)
  report_problems(now)
  send_uav_status(now)
  update_mount_target(now)
  update_camera()
  report_debug(now)
  return update, UPDATE_INTERVAL_MS
end

return update()
