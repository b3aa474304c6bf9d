"""Workflows: complete jobs over trials (angles, marker uncertainty, batch reports, the
demo, fuzzy dynamics), each reading its input once. The command line is a thin layer
over these."""
