"""Tool surfaces (Bezier, Nagata, facets), the contact search on them, and analytic shapes
to test them against."""
