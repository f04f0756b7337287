"""ArduPilot's scripting side, emulated: a Lua mount driver run against the simulated gimbal."""
