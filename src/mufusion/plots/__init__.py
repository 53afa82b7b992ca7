"""mufusion.plots"""
