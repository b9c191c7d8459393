// MotionBvh: being written.
