// test_motion_bvh: being written.
