// MotionDeepMimic: being written.
