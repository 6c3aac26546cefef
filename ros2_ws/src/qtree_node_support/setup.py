from setuptools import find_packages, setup

package_name = 'qtree_node_support'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='qtree-tamp developers',
    maintainer_email='dev@qtree-tamp.example',
    description='Node lifecycle (exit 0 on SIGINT/SIGTERM), service/action QoS and text clipping shared by the qtree-tamp nodes.',
    license='Apache-2.0',
)
