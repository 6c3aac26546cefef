"""Q-Tree task planner: tree-based Q-learning over sequences of relocated objects."""
