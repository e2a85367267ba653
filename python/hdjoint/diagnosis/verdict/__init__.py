"""The verdict: noise floors, resized parameters, detection limits, the findings document."""
