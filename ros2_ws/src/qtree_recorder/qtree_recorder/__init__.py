"""Records every topic of the qtree-tamp graph to MCAP (rosbag2 conventions) and to Rerun; offline replay."""
