// test_motion_csv_deepmimic: being written.
