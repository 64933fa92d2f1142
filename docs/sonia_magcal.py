#!/usr/bin/env python3
"""Horizontal hard/soft-iron fit of the SONIA GX3-25 magnetometer (docs/sonia.md).

auvnav-calibrate-mag refuses the SONIA runs: they turn about the vertical only
(tilt < 9 deg), so the vertical offset and scale are not observable and the 3-D
ellipsoid is not determined. This fits what a level turn does determine: the
readings in body axes (diag(1, -1, -1) raw, as config/import/sonia_pool_2016.yaml),
levelled with the accelerometer's roll/pitch (1 s moving mean), lie on an ellipse
in the horizontal plane; an algebraic conic fit gives its centre (hard iron x, y)
and shape (a symmetric 2x2 soft iron with determinant 1). The vertical offset is
left at 0. Prints the values config/sonia.yaml uses, the fit residual, and the
field the calibrated readings measure (horizontal, vertical, |B|, dip).
Pure Python (no numpy in Debian's base install); reads imu.csv and mag.csv.

    python3 docs/sonia_magcal.py ../shared/data/sonia-pool-2016/2016-01-23_run2_heading
"""
import csv, math, sys


def solve(A, b):
    # Gauss-Jordan elimination with partial pivoting.
    n=len(b); M=[A[i][:]+[b[i]] for i in range(n)]
    for c in range(n):
        p=max(range(c,n), key=lambda r: abs(M[r][c])); M[c],M[p]=M[p],M[c]
        for r in range(n):
            if r!=c:
                f=M[r][c]/M[c][c]
                for k in range(c,n+1): M[r][k]-=f*M[c][k]
    return [M[i][n]/M[i][i] for i in range(n)]
d=sys.argv[1]
m=list(csv.DictReader(open(d+'/mag.csv'))); a=list(csv.DictReader(open(d+'/imu.csv')))
assert len(m)==len(a)
# body FRD = diag(1,-1,-1) raw; tilt from the accelerometer, 1 s moving mean
acc=[(float(r['acc_x_mps2']),-float(r['acc_y_mps2']),-float(r['acc_z_mps2'])) for r in a]
B=[(float(r['mag_x_T'])*1e6,-float(r['mag_y_T'])*1e6,-float(r['mag_z_T'])*1e6) for r in m]
N=len(B); W=50
pts=[]; zs=[]
for i in range(N):
    lo=max(0,i-W); hi=min(N,i+W+1)
    fx=sum(x[0] for x in acc[lo:hi])/(hi-lo); fy=sum(x[1] for x in acc[lo:hi])/(hi-lo); fz=sum(x[2] for x in acc[lo:hi])/(hi-lo)
    roll=math.atan2(-fy,-fz); pitch=math.atan2(fx,math.hypot(fy,fz))
    x,y,z=B[i]
    # level: R = Ry(pitch) Rx(roll) applied to body vector (n = R_nb b with yaw 0)
    y1=math.cos(roll)*y-math.sin(roll)*z; z1=math.sin(roll)*y+math.cos(roll)*z
    x2=math.cos(pitch)*x+math.sin(pitch)*z1; z2=-math.sin(pitch)*x+math.cos(pitch)*z1
    pts.append((x2,y1)); zs.append(z2)
# conic A x^2 + B xy + C y^2 + D x + E y = 1
AtA=[[0]*5 for _ in range(5)]; Atb=[0]*5
for x,y in pts:
    r=[x*x,x*y,y*y,x,y]
    for i in range(5):
        Atb[i]+=r[i]
        for j in range(5): AtA[i][j]+=r[i]*r[j]
A_,B_,C_,D_,E_=solve(AtA,Atb)
cx,cy=solve([[2*A_,B_],[B_,2*C_]],[-D_,-E_])
k=1+A_*cx*cx+B_*cx*cy+C_*cy*cy
M=[[A_/k,B_/2/k],[B_/2/k,C_/k]]
# sqrt of 2x2 SPD
tr=M[0][0]+M[1][1]; det=M[0][0]*M[1][1]-M[0][1]**2; s=math.sqrt(det); t=math.sqrt(tr+2*s)
Q=[[(M[0][0]+s)/t,M[0][1]/t],[M[0][1]/t,(M[1][1]+s)/t]]  # sqrt(M): |Q (p-c)| = 1
dq=Q[0][0]*Q[1][1]-Q[0][1]**2; Hc=1/math.sqrt(dq)  # radius with det(Winv)=1
Wm=[[Q[i][j]*Hc for j in range(2)] for i in range(2)]  # S^-1 (2x2), det 1
dw=Wm[0][0]*Wm[1][1]-Wm[0][1]**2
S=[[Wm[1][1]/dw,-Wm[0][1]/dw],[-Wm[1][0]/dw,Wm[0][0]/dw]]
res=[]
for (x,y) in pts:
    u=x-cx; v=y-cy; hx=Wm[0][0]*u+Wm[0][1]*v; hy=Wm[1][0]*u+Wm[1][1]*v; res.append(math.hypot(hx,hy)-Hc)
rms=math.sqrt(sum(r*r for r in res)/len(res))
Z=sum(zs)/len(zs); zsd=math.sqrt(sum((z-Z)**2 for z in zs)/len(zs))
print("samples %d  hard iron xy [%.2f, %.2f] uT  soft iron 2x2 [[%.4f, %.4f], [%.4f, %.4f]]"%(N,cx,cy,S[0][0],S[0][1],S[1][0],S[1][1]))
print("horizontal %.2f uT (rms residual %.2f uT, %.2f deg)  vertical %.2f +- %.2f uT  |B| %.2f uT  dip %.2f deg"%(Hc,rms,math.degrees(rms/Hc),Z,zsd,math.hypot(Hc,Z),math.degrees(math.atan2(Z,Hc))))
# circle-only (no soft iron) for comparison: Kasa fit
AtA=[[0]*3 for _ in range(3)]; Atb=[0]*3
for x,y in pts:
    r=[x,y,1]; bb=x*x+y*y
    for i in range(3):
        Atb[i]+=r[i]*bb
        for j in range(3): AtA[i][j]+=r[i]*r[j]
p=solve(AtA,Atb); ccx=p[0]/2; ccy=p[1]/2; R=math.sqrt(p[2]+ccx*ccx+ccy*ccy)
rr=[math.hypot(x-ccx,y-ccy)-R for x,y in pts]
print("circle only: centre [%.2f, %.2f] radius %.2f rms %.2f uT"%(ccx,ccy,R,math.sqrt(sum(r*r for r in rr)/len(rr))))
