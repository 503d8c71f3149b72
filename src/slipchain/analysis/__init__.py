"""From stored results to numbers: sweep statistics, the paper's Fig. 6 claims, the mechanism, model beside experiment, reports."""
