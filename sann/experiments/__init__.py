"""What `python -m sann reproduce ...` runs: the paper's experiments, end to end."""
