"""mufusion.planner"""
