"""mufusion.road"""
