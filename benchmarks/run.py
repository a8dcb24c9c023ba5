#!/usr/bin/env python
"""Run, resume or report the validation studies (benchmarks/studies/); see benchmarks/harness.py.

    python benchmarks/run.py --list
    python benchmarks/run.py equipartition            # measure, summarize, write the page
    python benchmarks/run.py all --quick              # every study's smoke run
    python benchmarks/run.py all --report             # every page and figure from benchmarks/data/
"""

import harness

if __name__ == "__main__":
    harness.main()
