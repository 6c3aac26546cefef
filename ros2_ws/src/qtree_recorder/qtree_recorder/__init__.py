"""Recording of the qtree-tamp graph to MCAP (rosbag2 conventions) and Rerun; replay."""
