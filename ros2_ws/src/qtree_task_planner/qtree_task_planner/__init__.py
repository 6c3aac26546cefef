"""Q-Tree task planner (tree-based Q-learning over sequences of relocated objects), served as qtree_msgs/action/RetrieveTarget."""
