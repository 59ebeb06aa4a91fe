#!/usr/bin/env python3
# Evaluation side only (reads the dataset's ground truth, as `rsvio eval` does; never the estimator):
# which time shift d best aligns a run's rotation rates (consecutive trajectory.tum poses: camera
# frame, or body frame when its header says so) with the true rates over [a + d, b + d]? A
# global-shutter model on rolling-shutter images does not give the middle row's pose, and that can
# look like a camera-IMU time offset (docs/diagnose.md, "Rolling shutter from configs/default.json").
# Python 3, no third-party modules.
#
#   python3 scripts/rotation_time_shift.py RUN_DIR DATASET_DIR      (EuRoC layout with ground truth)
# Prints the RMS rate misfit at d = 0 and the best d over -40 .. +40 ms in 2 ms steps.
import sys, math, re
if len(sys.argv) != 3:
    sys.exit("usage: rotation_time_shift.py RUN_DIR DATASET_DIR")
run, data = sys.argv[1].rstrip('/'), sys.argv[2].rstrip('/')
def qmul(a,b):
    w1,x1,y1,z1=a; w2,x2,y2,z2=b
    return (w1*w2-x1*x2-y1*y2-z1*z2, w1*x2+x1*w2+y1*z2-z1*y2, w1*y2-x1*z2+y1*w2+z1*x2, w1*z2+x1*y2-y1*x2+z1*w2)
def qconj(q): return (q[0],-q[1],-q[2],-q[3])
def qlog(q):
    if q[0]<0: q=tuple(-c for c in q)
    v=q[1:]; n=math.sqrt(sum(c*c for c in v))
    if n<1e-12: return (0.0,0.0,0.0)
    a=2*math.atan2(n,q[0]); return tuple(a*c/n for c in v)
def rot2q(R):
    t=R[0][0]+R[1][1]+R[2][2]
    if t>0:
        s=math.sqrt(t+1)*2; return (0.25*s,(R[2][1]-R[1][2])/s,(R[0][2]-R[2][0])/s,(R[1][0]-R[0][1])/s)
    i=max(range(3),key=lambda k:R[k][k]); j=(i+1)%3; k=(i+2)%3
    s=math.sqrt(1+R[i][i]-R[j][j]-R[k][k])*2
    q=[0,0,0,0]; q[0]=(R[k][j]-R[j][k])/s; q[i+1]=0.25*s; q[j+1]=(R[j][i]+R[i][j])/s; q[k+1]=(R[k][i]+R[i][k])/s
    return tuple(q)
y=open(data+'/mav0/cam0/sensor.yaml').read()
nums=[float(x) for x in re.findall(r'[-0-9.e]+', y[y.index('T_BS'):].split('data:')[1].split(']')[0])]
q_BC=rot2q([nums[0:3],nums[4:7],nums[8:11]])
first = open(run + '/trajectory.tum').readline()
if 'frame: body' in first:
    q_BC = (1.0, 0.0, 0.0, 0.0)  # a visual-inertial run's body-frame trajectory: compare body rates
gt=[]
for l in open(data+'/mav0/state_groundtruth_estimate0/data.csv'):
    if l.startswith('#'): continue
    f=l.split(','); gt.append((int(f[0])*1e-9, qmul(tuple(float(c) for c in f[4:8]), q_BC)))
t0=gt[0][0]; dtg=gt[1][0]-gt[0][0]
def qslerp_at(t):
    i=int((t-t0)/dtg); i=max(0,min(len(gt)-2,i))
    (ta,qa),(tb,qb)=gt[i],gt[i+1]; u=(t-ta)/(tb-ta)
    d=qlog(qmul(qconj(qa),qb)); h=tuple(u*c/2 for c in d); n=math.sqrt(sum(c*c for c in h))
    dq=(math.cos(n),)+tuple((math.sin(n)/n if n>1e-12 else 1)*c for c in h)
    return qmul(qa,dq)
est=[]
for l in open(run+'/trajectory.tum'):
    if l.startswith('#'): continue
    f=[float(c) for c in l.split()]; est.append((f[0],(f[7],f[4],f[5],f[6])))
def misfit(d):
    s=0;n=0
    for (ta,qa),(tb,qb) in zip(est,est[1:]):
        we=qlog(qmul(qconj(qa),qb)); wt=qlog(qmul(qconj(qslerp_at(ta+d)),qslerp_at(tb+d)))
        dt=tb-ta; s+=sum(((a-b)/dt)**2 for a,b in zip(we,wt)); n+=1
    return math.sqrt(s/n)*180/math.pi, n
res=[(misfit(d/1000.0),d) for d in range(-40,41,2)]
best=min(res)
print('%s: pairs %d, misfit at 0: %.2f deg/s, best shift %+d ms: %.2f deg/s' % (run, res[0][0][1], [r for r in res if r[1]==0][0][0][0], best[1], best[0][0]))
