# exported for the karst tests: the same plane as two_parts.ts given as depths below datum
GOCAD TSurf 1
HDR name:depth_plane
GOCAD_ORIGINAL_COORDINATE_SYSTEM
NAME "local depth"
AXIS_NAME "X" "Y" "Z"
AXIS_UNIT "m" "m" "m"
ZPOSITIVE Depth
END_ORIGINAL_COORDINATE_SYSTEM
TFACE
VRTX 10 0 0 -10
VRTX 20 100 0 -20
VRTX 30 0 100 -30
VRTX 40 100 100 -40
TRGL 10 20 40
TRGL 10 40 30
END
