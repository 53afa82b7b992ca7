"""mufusion.fusion"""
