// MotionCsv: being written.
