// test_motion: being written.
