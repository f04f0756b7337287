"""A simulated gimbal, UAV and ground station that speak the protocol, for demos and tests."""
