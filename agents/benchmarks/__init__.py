"""Speed and quality benchmarks run by ``poc-env bench env|plan|train`` (one line per figure)."""
