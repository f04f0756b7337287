"""The bench check (`gimbal-analyzer check`): steps, their run on a live link, and verdicts."""
