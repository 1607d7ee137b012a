"""The methods: one module (or package) per method, with its config, named state and
hooks. A method imports the shared parts, never another method (but the one it is a
variant of).
"""
