"""mufusion.sim"""
