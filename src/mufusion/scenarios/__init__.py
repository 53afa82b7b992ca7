"""mufusion.scenarios"""
