"""mufusion.vehicle"""
