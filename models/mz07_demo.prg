# NACHI MZ07 demo program (models/mz07.yaml): run with
#   fitup run models/mz07_demo.prg --doc models/mz07.yaml --robot mz07
# or from a script: doc.robot("mz07").run_program("models/mz07_demo.prg").
# Poses: world x y z (mm) and a b c (degrees, fixed X-Y-Z); tool pointing down is 0 0 0.
Speed 200                      # TCP speed, mm/s
JointSpeed 60                  # deg/s
Interval 0.05                  # s between logged samples
Joint 0 0 0 0 0 0              # home: tool point at (390, 0, 198.1)
Line 390 0 300 0 0 0           # straight up 101.9 mm
Line 450 100 300 0 0 0
Circle 500 50 300 0 0 0   450 0 300 0 0 0     # arc through (500, 50) to (450, 0)
Line 390 0 300 0 0 15          # back, turning the tool 15° about Z
Joint 20 -10 10 0 0 0          # joint move, degrees
