import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'qtree_scene'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['scenarios/*']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        (os.path.join('share', package_name, 'scenarios'), glob('qtree_scene/scenarios/*')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='qtree-tamp developers',
    maintainer_email='dev@qtree-tamp.example',
    description='Scene types, scenario YAML loader/validator, Scene message conversions, scenarios S1-S3 and the clutter generator.',
    license='Apache-2.0',
)
