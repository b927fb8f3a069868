"""Saves a robot as Pinocchio reads it from its URDF, in Pinocchio's text archive, for
`aba saved` (generator/benches/pinocchio/aba.cpp) to load; prints its nq and nv.

    python save_robot.py ROBOT.urdf fixed|floating OUT.txt

`floating` roots the robot on a free flyer. Mimic joints are read as independent joints (ABA
takes no mimic joint).
"""

import sys

import pinocchio as pin

urdf, base, out = sys.argv[1:4]
model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer()) if base == "floating" else pin.buildModelFromUrdf(urdf)
model.saveToText(out)
print(model.nq, model.nv)
