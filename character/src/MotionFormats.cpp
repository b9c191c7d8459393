// MotionFormats: being written.
