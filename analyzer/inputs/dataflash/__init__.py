"""ArduPilot DataFlash logs (.bin): FMT-described records, CANF / CAFD frames on GPS time."""
