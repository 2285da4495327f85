# Demo program for the URDF arm `arm6` (models/urdf/fitup_arm6.urdf) placed at
# (0, 1500, 0) by scripts/robot_urdf.rhai. Poses: world x y z (mm), a b c (degrees,
# fixed X-Y-Z); tool pointing down is 180 0 180 for this arm.
Speed 200                      # TCP speed, mm/s
JointSpeed 60                  # deg/s
Interval 0.05                  # s between logged samples
Joint 0 30 20 0 40 0           # start: tool down at (895.459, 1500, 525.425)
Line 895.459 1500 425 180 0 180                            # 100 mm down
Line 895.459 1600 425 180 0 180
Circle 945.459 1550 425 180 0 180   895.459 1500 425 180 0 180   # half circle back
Line 895.459 1500 525 180 0 165                            # up, turning the tool 15°
