"""The simulated camera: the simulated gimbal's view rendered, encoded as H.264 and recorded."""
