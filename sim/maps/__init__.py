"""Maps: Moving AI ``.map`` files and ``.scen`` lists, seeded map generators, obstacle layouts.
"""
