"""Where the gimbal points and what it was told to look at: transforms, 3D scene, overlays."""
